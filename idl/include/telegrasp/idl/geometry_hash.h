// The content hash of ObjectGeometry (telegrasp.idl): shared by the server, which computes it,
// and the client library, which checks what arrived and caches meshes by it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace telegrasp::idl {

/// FNV-1a 64-bit offset basis: the hash of no bytes.
inline constexpr std::uint64_t kFnv1a64Basis = 0xcbf29ce484222325ull;

/// Continues the FNV-1a 64-bit hash `h` over the four little-endian bytes of `value`.
inline std::uint64_t fnv1a64_u32(std::uint64_t h, std::uint32_t value) {
  for (int byte = 0; byte < 4; ++byte) {
    h ^= (value >> (8 * byte)) & 0xffu;
    h *= 0x100000001b3ull;
  }
  return h;
}

/// ObjectGeometry.content_hash of a mesh given as `vertex_count` x (x, y, z) float32 coordinates
/// and `triangle_count` x 3 uint32 indices: FNV-1a 64 over vertex_count and triangle_count, then
/// every coordinate's IEEE-754 bits, then every index, each as four little-endian bytes. The same
/// value on any host, whatever its byte order. Not a cryptographic hash: it identifies a shape and
/// detects damage, it does not authenticate (DDS Security does that).
inline std::uint64_t geometry_content_hash(const float* xyz, std::size_t vertex_count, const std::uint32_t* indices,
                                           std::size_t triangle_count) {
  std::uint64_t h = fnv1a64_u32(kFnv1a64Basis, static_cast<std::uint32_t>(vertex_count));
  h = fnv1a64_u32(h, static_cast<std::uint32_t>(triangle_count));
  for (std::size_t i = 0; i < 3 * vertex_count; ++i) {
    std::uint32_t bits;
    std::memcpy(&bits, &xyz[i], sizeof bits);
    h = fnv1a64_u32(h, bits);
  }
  for (std::size_t i = 0; i < 3 * triangle_count; ++i) h = fnv1a64_u32(h, indices[i]);
  return h;
}

}  // namespace telegrasp::idl
