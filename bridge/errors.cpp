#include "bridge/errors.hpp"

#include <sys/resource.h>

#include <iomanip>
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

namespace {
std::string showBytes(double gb) {
  std::ostringstream os;
  os << std::setprecision(3);
  if (gb >= 1.0)
    os << gb << " GB";
  else if (gb >= 1e-3)
    os << gb * 1e3 << " MB";
  else
    os << gb * 1e6 << " kB";
  return os.str();
}

std::string describeWrite(const std::string& file, const std::string& detail) {
  std::ostringstream os;
  os << "cannot write " << file << ": " << detail;
  std::error_code ec;
  const auto folder = std::filesystem::path(file).parent_path();
  const auto space = std::filesystem::space(folder.empty() ? std::filesystem::path(".") : folder, ec);
  if (!ec) {
    const double gb = static_cast<double>(space.available) / 1e9;
    os << std::setprecision(3) << " (the disk holding it has "
       << (gb < 1e-4 ? std::string("no room left: it is full") : showBytes(gb) + " free");
    rlimit limit{};
    if (getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
      os << "; files are limited to " << showBytes(static_cast<double>(limit.rlim_cur) / 1e9) << " (ulimit -f)";
    os << ")";
  }
  return os.str();
}
}  // namespace

WriteError::WriteError(const std::string& file, const std::string& detail)
    : std::runtime_error(describeWrite(file, detail)) {}

}  // namespace gabion::bridge
