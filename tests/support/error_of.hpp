#pragma once
// Checking errors by their words: the message of the exception a call throws, and a check that a
// text contains a part.

#include <gtest/gtest.h>

#include <exception>
#include <string>

/// Expects `text` to contain `part`, and prints both when it does not.
#define EXPECT_CONTAINS(text, part)                           \
    do {                                                      \
        const std::string text_ = (text), part_ = (part);     \
        EXPECT_NE(text_.find(part_), std::string::npos)       \
            << "  text: " << text_ << "\n  lacks: " << part_; \
    } while (0)

namespace esf::test {

/// Runs f() and returns the what() of the exception of type E it throws; a fixed text naming the
/// problem when it throws nothing (or, with E, another type escapes the test as a failure).
template <class E = std::exception, class F>
std::string error_of(F&& f) {
    try {
        f();
    } catch (const E& e) {
        return e.what();
    }
    return "(no exception of the expected type)";
}

}  // namespace esf::test
