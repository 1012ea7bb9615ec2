#pragma once
// The message of the exception a call throws, for tests that check errors by their words.

#include <exception>
#include <string>

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
