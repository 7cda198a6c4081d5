#pragma once
// The bytes libFuzzer gives, as a file the loaders read (every reader of
// Gabion takes a path: it names the file in its errors). One file per
// process, rewritten for each input.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace gabion::fuzz {

inline std::filesystem::path inputFile(const uint8_t* data, size_t size, const std::string& extension) {
  const auto path = std::filesystem::temp_directory_path() / ("gabion_fuzz_" + std::to_string(::getpid()) + extension);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

}  // namespace gabion::fuzz
