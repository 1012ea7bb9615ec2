#include "core/number_text.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <system_error>

namespace esf::detail {

namespace {

/// A leading '+' is accepted (std::from_chars refuses it), but not "+-1" or "++1".
std::string_view without_plus(std::string_view token) {
    if (token.size() > 1 && token[0] == '+' && token[1] != '-' && token[1] != '+') {
        token.remove_prefix(1);
    }
    return token;
}

/// Rough decimal exponent of a number std::from_chars found out of range even as a double:
/// negative for tiny values (underflow), positive for huge ones. Only its sign is used.
long long decimal_exponent(std::string_view token) {
    std::size_t i = 0;
    if (i < token.size() && (token[i] == '-' || token[i] == '+')) ++i;
    long long before_point = 0, leading_zeros_after_point = 0;
    bool seen_point = false, seen_digit = false;
    for (; i < token.size() && token[i] != 'e' && token[i] != 'E'; ++i) {
        const char c = token[i];
        if (c == '.') {
            seen_point = true;
        } else if (!seen_point) {
            if (c != '0' || seen_digit) {
                seen_digit = true;
                ++before_point;
            }
        } else if (!seen_digit) {
            if (c == '0') {
                ++leading_zeros_after_point;
            } else {
                seen_digit = true;
            }
        }
    }
    long long exponent = 0;
    if (i + 1 < token.size()) {
        const char* first = token.data() + i + 1;
        if (*first == '+') ++first;
        const auto [ptr, ec] = std::from_chars(first, token.data() + token.size(), exponent);
        if (ec == std::errc::result_out_of_range) {
            exponent = *first == '-' ? std::numeric_limits<long long>::min() / 2
                                     : std::numeric_limits<long long>::max() / 2;
        }
        (void)ptr;
    }
    return exponent + (before_point > 0 ? before_point : -leading_zeros_after_point);
}

/// Parses a whole token as T. std::from_chars reports both overflow and underflow to zero as
/// out of range; underflow is a correct signed zero, overflow is kOutOfRange. (Subnormal results
/// such as 1e-40 in a float come back from std::from_chars as they are.)
template <class T>
NumberText parse_whole(std::string_view token, T& value) {
    token = without_plus(token);
    const char* end = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(token.data(), end, value);
    if (ptr != end) return NumberText::kNotANumber;
    if (ec == std::errc()) return NumberText::kOk;
    if (ec != std::errc::result_out_of_range) return NumberText::kNotANumber;
    if (decimal_exponent(token) > 0) return NumberText::kOutOfRange;
    value = token[0] == '-' ? -T(0) : T(0);
    return NumberText::kOk;
}

}  // namespace

NumberText parse_float_via_double(std::string_view token, float& value) {
    double wide = 0.0;
    const NumberText status = parse_whole(token, wide);
    if (status != NumberText::kOk) return status;
    value = static_cast<float>(wide);
    if (std::isinf(value) && !std::isinf(wide)) return NumberText::kOutOfRange;
    return NumberText::kOk;
}

NumberText parse_float(std::string_view token, float& value) { return parse_whole(token, value); }

bool parse_double(std::string_view token, double& value) {
    token = without_plus(token);
    const char* end = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(token.data(), end, value);
    return ec == std::errc() && ptr == end;
}

void append_float(std::string& out, float value) {
    if (std::isnan(value)) {
        out += "nan";
        return;
    }
    std::array<char, 32> buf{};
    const auto result = std::to_chars(buf.data(), buf.data() + buf.size(), value);
    out.append(buf.data(), result.ptr);
}

void append_uint(std::string& out, unsigned long long value) {
    std::array<char, 24> buf{};
    const auto result = std::to_chars(buf.data(), buf.data() + buf.size(), value);
    out.append(buf.data(), result.ptr);
}

namespace {

std::string printed(const char* format, int digits, double value) {
    std::array<char, 512> buf{};
    const int n = std::snprintf(buf.data(), buf.size(), format, digits, value);
    if (n < 0) return {};
    if (static_cast<std::size_t>(n) < buf.size())
        return std::string(buf.data(), static_cast<std::size_t>(n));
    std::string out(static_cast<std::size_t>(n) + 1, '\0');
    std::snprintf(out.data(), out.size(), format, digits, value);
    out.resize(static_cast<std::size_t>(n));
    return out;
}

}  // namespace

std::string fixed_text(double value, int digits) { return printed("%.*f", digits, value); }

std::string percent_text(double fraction, int digits) {
    return printed("%.*f", digits, 100.0 * fraction);
}

std::string significant_text(double value, int digits) { return printed("%.*g", digits, value); }

}  // namespace esf::detail
