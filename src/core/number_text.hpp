#pragma once
// Numbers in text: whole-token parsing with std::from_chars and shortest round-trip output with
// std::to_chars (no locale, no allocation) for files; fixed digits, percentages and significant
// digits for what people read (reports, messages, the command line's tables).

#include <string>
#include <string_view>

namespace esf::detail {

enum class NumberText {
    kOk,
    kNotANumber,  ///< not a number at all ("abc", "1.2.3", "0x10", "")
    kOutOfRange,  ///< a finite number beyond the float range, such as 1e39
};

/// Parses a whole token into a float: decimal or scientific, an optional sign (a leading '+'
/// too), "nan", "inf". Values below the float range round to 0 or a subnormal (1e-50 reads as
/// 0); finite values above it are kOutOfRange, never infinity.
NumberText parse_float(std::string_view token, float& value);

/// The same, rounded through double first (a field stored as double in the file, so that the
/// float is the one a double-then-float conversion gives).
NumberText parse_float_via_double(std::string_view token, float& value);

/// Whole-token double ("nan", "inf", a leading '+'); false on anything else, or out of range.
bool parse_double(std::string_view token, double& value);

/// Appends the shortest text that reads back as exactly `value`; NaN as "nan".
void append_float(std::string& out, float value);

/// Appends the decimal text of `value`.
void append_uint(std::string& out, unsigned long long value);

/// `value` with `digits` digits after the point, as printf's "%.*f": fixed_text(2.345, 1) is
/// "2.3".
std::string fixed_text(double value, int digits);

/// A fraction as a percentage without the sign, `digits` digits after the point:
/// percent_text(0.1234) is "12.3".
std::string percent_text(double fraction, int digits = 1);

/// `value` with `digits` significant digits, as printf's "%.*g" (and as an ostream writes a
/// double with that precision): significant_text(0.000123456, 3) is "0.000123".
std::string significant_text(double value, int digits);

}  // namespace esf::detail
