#pragma once
// Runs the `gabion` binary of this build (GABION_BINARY) and captures its exit
// code and output, for tests of the command line's contract.
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace gabion::testing {

struct CliResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

/// Runs a shell command line and captures its exit code and output.
inline CliResult runCommand(const std::string& command_line) {
  const std::string cmd = command_line + " 2>&1";
  CliResult r;
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return r;
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), p) != nullptr) r.output += buf.data();
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

inline CliResult runGabion(const std::string& args) {
  return runCommand(std::string(GABION_BINARY) + " " + args);
}

/// Starts `gabion ARGS` in the background, waits until `file` appears (or
/// the run ends), then sends it `signal` ("KILL", "INT"); returns what the
/// shell printed, ending with "exit=N" (137 for a SIGKILL).
inline std::string signalWhenThere(const std::string& args, const std::filesystem::path& file, const char* signal) {
  return runCommand("sh -c '" + std::string(GABION_BINARY) + " " + args + " & p=$!; while [ ! -e " + file.string() +
                    " ] && kill -0 $p 2>/dev/null; do sleep 0.01; done; kill -" + signal +
                    " $p; wait $p; echo exit=$?'")
      .output;
}

/// A fresh scratch folder under the test temp dir, named by the test and
/// the process (two test runs on one machine never share one).
inline std::filesystem::path scratchDir(const std::string& name) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / ("gabion_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// A run's summary.json, parsed.
inline nlohmann::json summaryOf(const std::filesystem::path& outdir) {
  std::ifstream in(outdir / "summary.json");
  return nlohmann::json::parse(in);
}

inline void writeFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

}  // namespace gabion::testing
