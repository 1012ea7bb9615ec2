#pragma once
// FNV-1a, 64 bits (Fowler, Noll & Vo): the project's one fixed string hash, for seeds derived
// from names and for content fingerprints. Unlike std::hash it gives the same value with every
// library and platform. Not a security measure.

#include <cstdint>
#include <string_view>

namespace esf::detail {

inline constexpr std::uint64_t kFnv1aOffsetBasis = 0xcbf29ce484222325ull;
inline constexpr std::uint64_t kFnv1aPrime = 0x100000001b3ull;

/// The hash `hash` continued with one more byte.
constexpr std::uint64_t fnv1a_byte(std::uint64_t hash, unsigned char byte) {
    return (hash ^ byte) * kFnv1aPrime;
}

/// The hash `hash` continued with the bytes of `text` (from the start: the offset basis).
constexpr std::uint64_t fnv1a(std::string_view text, std::uint64_t hash = kFnv1aOffsetBasis) {
    for (const char c : text) hash = fnv1a_byte(hash, static_cast<unsigned char>(c));
    return hash;
}

}  // namespace esf::detail
