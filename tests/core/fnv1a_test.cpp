// The one string hash gives FNV-1a's published 64-bit values (seeds and fingerprints depend on
// them), and continues a hash byte by byte.

#include "core/fnv1a.hpp"

#include <gtest/gtest.h>

namespace {

using esf::detail::fnv1a;
using esf::detail::fnv1a_byte;

TEST(Fnv1a, PublishedValues) {
    EXPECT_EQ(fnv1a(""), 0xcbf29ce484222325ull);
    EXPECT_EQ(fnv1a("a"), 0xaf63dc4c8601ec8cull);
    EXPECT_EQ(fnv1a("foobar"), 0x85944171f73967e8ull);
}

TEST(Fnv1a, ContinuesAHash) {
    EXPECT_EQ(fnv1a("bar", fnv1a("foo")), fnv1a("foobar"));
    EXPECT_EQ(fnv1a_byte(fnv1a("fooba"), 'r'), fnv1a("foobar"));
    static_assert(fnv1a("a") == 0xaf63dc4c8601ec8cull);
}

}  // namespace
