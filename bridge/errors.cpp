#include "bridge/errors.hpp"

#include <sstream>

namespace gabion::bridge {

namespace {
std::string joinLocation(const std::string& file, const std::string& pointer, const std::string& message) {
  std::string out = file.empty() ? std::string("<input>") : file;
  if (!pointer.empty()) out += ": " + pointer;
  return out + ": " + message;
}
std::string describeStep(long long step, double time_s, const std::string& message) {
  std::ostringstream os;
  os << "step " << step << ", t = " << time_s << " s: " << message;
  return os.str();
}
}  // namespace

InputError::InputError(std::string file, std::string pointer, std::string message)
    : std::runtime_error(joinLocation(file, pointer, message)),
      file_(std::move(file)),
      pointer_(std::move(pointer)),
      message_(std::move(message)) {}

NumericalError::NumericalError(long long step, double time_s, const std::string& message)
    : std::runtime_error(describeStep(step, time_s, message)), step_(step), time_s_(time_s) {}

}  // namespace gabion::bridge
