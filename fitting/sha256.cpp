// SHA-256 by Nettle (Debian nettle-dev): the provenance hashes of input files.
#include "fitting/sha256.hpp"

#include <nettle/sha2.h>

#include <array>
#include <cstdio>
#include <fstream>

#include "bridge/errors.hpp"

namespace gabion::fitting {

namespace {

std::string hex(const std::array<std::uint8_t, SHA256_DIGEST_SIZE>& digest) {
  static const char* d = "0123456789abcdef";
  std::string out;
  for (const std::uint8_t b : digest) out += {d[b >> 4], d[b & 15]};
  return out;
}

}  // namespace

std::string sha256Hex(const std::string& data) {
  sha256_ctx ctx;
  sha256_init(&ctx);
  sha256_update(&ctx, data.size(), reinterpret_cast<const std::uint8_t*>(data.data()));
  std::array<std::uint8_t, SHA256_DIGEST_SIZE> digest{};
  sha256_digest(&ctx, digest.size(), digest.data());
  return hex(digest);
}

std::string sha256File(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw bridge::InputError(file.string(), "", "cannot open file to hash it");
  sha256_ctx ctx;
  sha256_init(&ctx);
  std::array<char, 1 << 16> buffer{};
  while (in) {
    in.read(buffer.data(), buffer.size());
    const auto n = static_cast<std::size_t>(in.gcount());
    if (n > 0) sha256_update(&ctx, n, reinterpret_cast<const std::uint8_t*>(buffer.data()));
  }
  if (in.bad()) throw bridge::InputError(file.string(), "", "read error while hashing it");
  std::array<std::uint8_t, SHA256_DIGEST_SIZE> digest{};
  sha256_digest(&ctx, digest.size(), digest.data());
  return hex(digest);
}

}  // namespace gabion::fitting
