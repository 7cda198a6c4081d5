#pragma once
/// \file
/// The failures that cross module boundaries (STYLE.md rule 6):
/// bad input is an exception thrown at load time; numerical trouble is a
/// status that a run reports and stops on (modules turn it into a RunOutcome).
#include <filesystem>
#include <stdexcept>
#include <string>

namespace gabion::bridge {

/// Bad input: a file that cannot be read or a value that is missing, unknown,
/// of the wrong type or out of range. what() reads "file: /json/pointer: message".
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string pointer, std::string message);
  const std::string& file() const { return file_; }
  const std::string& pointer() const { return pointer_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_, pointer_, message_;
};

/// Numerical failure inside a run (NaN, runaway energy, excessive overlap,
/// time step above critical). Carries where it happened.
class NumericalError : public std::runtime_error {
 public:
  NumericalError(long long step, double time_s, const std::string& message);
  long long step() const { return step_; }
  double time_s() const { return time_s_; }

 private:
  long long step_;
  double time_s_;
};

/// A result file that could not be written (a full disk, a file-size limit,
/// a folder that went away). what() names the file and says how much room
/// the disk holding it has left. The run ends with exit 1; the file's
/// earlier complete version, if any, is left as it was (bridge/output.hpp).
class WriteError : public std::runtime_error {
 public:
  WriteError(const std::string& file, const std::string& detail);
};

}  // namespace gabion::bridge
