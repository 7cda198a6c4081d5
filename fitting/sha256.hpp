#pragma once
/// \file
/// SHA-256 of a file (FIPS 180-4, computed by Nettle), for the provenance of
/// fitted laws (which exact input files a law was identified from) and the
/// pipeline's stage keys.
#include <filesystem>
#include <string>

namespace gabion::fitting {

/// Lower-case hex SHA-256 of `data`.
std::string sha256Hex(const std::string& data);
/// Lower-case hex SHA-256 of a file's bytes; throws bridge::InputError when unreadable.
std::string sha256File(const std::filesystem::path& file);

}  // namespace gabion::fitting
