#pragma once
/// \file
/// An output folder is committed as a set. Every result file is written
/// under a temporary name and renamed when complete (bridge/output.hpp); the
/// writers note each file they complete. When a run ends (ok, failed or
/// interrupted), `manifest.json` is written last, listing the files this run
/// wrote (or adopted: a pipeline's reused stages) with their sizes. A run
/// removes the folder's manifest before it writes anything, so a folder whose
/// run was killed has none. Readers trust only what a manifest lists: a file
/// beside it that it does not list is from an earlier run or the user's.
///
/// manifest.json: {"format": "gabion.manifest/1", "status": "ok", "files":
/// [{"path": "result.h5", "bytes": 297368}, ...]}, paths relative to the
/// folder, sorted.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace gabion::bridge {

/// Records that `file` was completely written by this process (called by
/// the atomic writers; thread-safe).
void noteWritten(const std::filesystem::path& file);

/// Starts a run in `folder`: removes its manifest.json, so the folder's
/// earlier set is no longer trusted while the run writes.
void beginManifest(const std::filesystem::path& folder);

/// The files noted under `folder` since beginManifest, relative, sorted,
/// those that still exist.
std::vector<std::filesystem::path> writtenFiles(const std::filesystem::path& folder);

/// Notes every file listed by `folder`'s manifest (a stage reused as it is),
/// so that the enclosing run's manifest lists them. Returns false (noting
/// nothing) when the folder has no valid manifest or a listed file is
/// missing or changed size.
bool adoptManifest(const std::filesystem::path& folder);

/// Writes `folder`/manifest.json listing writtenFiles(folder), with the run's
/// status ("ok", "numerical_failure", "interrupted").
void writeManifest(const std::filesystem::path& folder, const std::string& status);

/// Throws InputError unless `file` is listed, with its present size, by the
/// nearest manifest in its folder or a folder above it (up to 4 levels): a
/// file left by an earlier run is not read as a result. With no manifest
/// at all: an error (the run was killed), unless `unmanaged_ok` (a file made
/// elsewhere: lab data, a cell given by path).
void requireListed(const std::filesystem::path& file, bool unmanaged_ok = false);

}  // namespace gabion::bridge
