#include "bridge/manifest.hpp"

#include <algorithm>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"

namespace gabion::bridge {

namespace fs = std::filesystem;

namespace {

constexpr const char* kManifest = "manifest.json";

std::mutex& registryMutex() {
  static std::mutex m;
  return m;
}
std::set<fs::path>& registry() {
  static std::set<fs::path> files;
  return files;
}

fs::path absoluteOf(const fs::path& p) {
  std::error_code ec;
  const fs::path a = fs::weakly_canonical(fs::absolute(p, ec), ec);
  return ec ? fs::absolute(p).lexically_normal() : a;
}

// `file` relative to `folder` when it lies inside it.
bool inside(const fs::path& folder, const fs::path& file, fs::path& relative) {
  const fs::path r = file.lexically_relative(folder);
  if (r.empty() || *r.begin() == "..") return false;
  relative = r;
  return true;
}

// The manifest's files as (relative path, bytes); empty on any error.
bool readManifest(const fs::path& folder, std::vector<std::pair<fs::path, std::uintmax_t>>& files) {
  std::ifstream in(folder / kManifest);
  if (!in) return false;
  try {
    const nlohmann::json m = nlohmann::json::parse(in);
    if (m.value("format", "") != "gabion.manifest/1") return false;
    for (const auto& f : m.at("files"))
      files.emplace_back(f.at("path").get<std::string>(), f.at("bytes").get<std::uintmax_t>());
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

}  // namespace

void noteWritten(const fs::path& file) {
  const fs::path a = absoluteOf(file);
  const std::lock_guard<std::mutex> lock(registryMutex());
  registry().insert(a);
}

void beginManifest(const fs::path& folder) {
  std::error_code ec;
  fs::remove(folder / kManifest, ec);
}

std::vector<fs::path> writtenFiles(const fs::path& folder) {
  const fs::path root = absoluteOf(folder);
  std::vector<fs::path> out;
  const std::lock_guard<std::mutex> lock(registryMutex());
  for (const fs::path& f : registry()) {
    fs::path rel;
    std::error_code ec;
    if (inside(root, f, rel) && rel != kManifest && fs::is_regular_file(f, ec)) out.push_back(rel);
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool adoptManifest(const fs::path& folder) {
  std::vector<std::pair<fs::path, std::uintmax_t>> files;
  if (!readManifest(folder, files)) return false;
  for (const auto& [rel, bytes] : files) {
    std::error_code ec;
    if (fs::file_size(folder / rel, ec) != bytes || ec) return false;
  }
  for (const auto& f : files) noteWritten(folder / f.first);
  noteWritten(folder / kManifest);
  return true;
}

void writeManifest(const fs::path& folder, const std::string& status) {
  nlohmann::json files = nlohmann::json::array();
  for (const fs::path& rel : writtenFiles(folder)) {
    std::error_code ec;
    const std::uintmax_t bytes = fs::file_size(folder / rel, ec);
    if (!ec) files.push_back({{"path", rel.generic_string()}, {"bytes", bytes}});
  }
  writeJsonAtomic(folder / kManifest, {{"format", "gabion.manifest/1"}, {"status", status}, {"files", files}});
}

void requireListed(const fs::path& file, bool unmanaged_ok) {
  const fs::path a = absoluteOf(file);
  fs::path folder = a.parent_path();
  for (int up = 0; up < 5; ++up, folder = folder.parent_path()) {
    std::error_code ec;
    if (fs::exists(folder / kManifest, ec)) {
      std::vector<std::pair<fs::path, std::uintmax_t>> files;
      if (!readManifest(folder, files))
        throw InputError(file.string(), "", "the run's manifest " + (folder / kManifest).string() + " is unreadable");
      const fs::path rel = a.lexically_relative(folder);
      for (const auto& [path, bytes] : files) {
        if (path != rel) continue;
        if (fs::file_size(a, ec) != bytes || ec)
          throw InputError(file.string(), "",
                           "changed since its run listed it in " + (folder / kManifest).string() + " (" +
                               std::to_string(bytes) + " bytes then)");
        return;
      }
      throw InputError(file.string(), "",
                       "not listed in " + (folder / kManifest).string() +
                           ": it is not from the run that wrote that folder (an earlier run's, or one that run did "
                           "not finish writing)");
    }
    if (folder == folder.parent_path()) break;
  }
  if (!unmanaged_ok)
    throw InputError(file.string(), "",
                     "no manifest.json beside it or above it: the run that wrote it did not finish (killed?), or "
                     "it is not a Gabion result");
}

}  // namespace gabion::bridge
