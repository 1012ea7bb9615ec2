// Numbers in text (src/core/number_text.cpp): whole tokens, the float range, shortest output.

#include "core/number_text.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>

namespace {

using esf::detail::NumberText;

NumberText parse(const std::string& token, float& value) {
    return esf::detail::parse_float(token, value);
}

TEST(NumberText, WholeTokensOnly) {
    float v = 0;
    EXPECT_EQ(parse("1.5", v), NumberText::kOk);
    EXPECT_EQ(v, 1.5f);
    EXPECT_EQ(parse("+2", v), NumberText::kOk);
    EXPECT_EQ(v, 2.0f);
    EXPECT_EQ(parse("-2.5e2", v), NumberText::kOk);
    EXPECT_EQ(v, -250.0f);
    EXPECT_EQ(parse("nan", v), NumberText::kOk);
    EXPECT_TRUE(std::isnan(v));
    EXPECT_EQ(parse("-inf", v), NumberText::kOk);
    EXPECT_EQ(v, -std::numeric_limits<float>::infinity());
    for (const char* bad : {"", "+", "abc", "1.2.3", "0x10", "1e", "+-1", "++1", "1,5", " 1"}) {
        EXPECT_EQ(parse(bad, v), NumberText::kNotANumber) << "'" << bad << "'";
    }
}

TEST(NumberText, OverflowIsAnErrorUnderflowIsZeroOrSubnormal) {
    float v = 1;
    for (const char* big : {"1e39", "-1e39", "3.5e38", "1e400", "1e99999999999999999999",
                            "123456789012345678901234567890123456789012345"}) {
        EXPECT_EQ(parse(big, v), NumberText::kOutOfRange) << big;
    }
    EXPECT_EQ(parse("3.4028235e38", v), NumberText::kOk);
    EXPECT_EQ(v, std::numeric_limits<float>::max());
    for (const char* tiny : {"1e-50", "1e-400", "1e-99999999999999999999",
                             "0.0000000000000000000000"
                             "000000000000000000000000001"}) {
        v = 1;
        EXPECT_EQ(parse(tiny, v), NumberText::kOk) << tiny;
        EXPECT_EQ(std::bit_cast<std::uint32_t>(v), 0u) << tiny;
    }
    EXPECT_EQ(parse("-1e-50", v), NumberText::kOk);
    EXPECT_EQ(std::bit_cast<std::uint32_t>(v), std::bit_cast<std::uint32_t>(-0.0f));
    EXPECT_EQ(parse("1e-40", v), NumberText::kOk);
    EXPECT_EQ(std::fpclassify(v), FP_SUBNORMAL);

    // Through double: 0.1 as a double, then rounded to float; 4e38 is beyond the float range.
    EXPECT_EQ(esf::detail::parse_float_via_double("0.1", v), NumberText::kOk);
    EXPECT_EQ(v, static_cast<float>(0.1));
    EXPECT_EQ(esf::detail::parse_float_via_double("4e38", v), NumberText::kOutOfRange);
    EXPECT_EQ(esf::detail::parse_float_via_double("1e-50", v), NumberText::kOk);
    EXPECT_EQ(v, 0.0f);
}

TEST(NumberText, ShortestOutputReadsBackBitForBit) {
    std::mt19937 gen(5);
    std::string out;
    for (int i = 0; i < 20000; ++i) {
        const float value = std::bit_cast<float>(static_cast<std::uint32_t>(gen()));
        out.clear();
        esf::detail::append_float(out, value);
        float back = 0;
        ASSERT_EQ(parse(out, back), NumberText::kOk) << out;
        if (std::isnan(value)) {
            EXPECT_EQ(out, "nan");
            EXPECT_TRUE(std::isnan(back));
        } else {
            ASSERT_EQ(std::bit_cast<std::uint32_t>(back), std::bit_cast<std::uint32_t>(value))
                << out;
            EXPECT_LE(out.size(), 15u) << out;  // "-1.17549435e-38" is the longest
        }
    }
    out.clear();
    esf::detail::append_float(out, 0.1f);
    EXPECT_EQ(out, "0.1");
}

TEST(NumberText, FixedPercentAndSignificantDigits) {
    using esf::detail::fixed_text;
    using esf::detail::percent_text;
    using esf::detail::significant_text;
    EXPECT_EQ(fixed_text(2.345, 1), "2.3");
    EXPECT_EQ(fixed_text(12.0, 2), "12.00");
    EXPECT_EQ(fixed_text(-0.5, 0), "-0");
    EXPECT_EQ(fixed_text(1e300, 1).size(), 303u);  // longer than any fixed buffer
    EXPECT_EQ(percent_text(0.1234), "12.3");
    EXPECT_EQ(percent_text(1.0), "100.0");
    EXPECT_EQ(percent_text(0.834, 0), "83");
    EXPECT_EQ(significant_text(0.000123456, 3), "0.000123");
    EXPECT_EQ(significant_text(1e18, 6), "1e+18");
    EXPECT_EQ(significant_text(0.1, 17), "0.10000000000000001");
    EXPECT_EQ(significant_text(30.0, 6), "30");
}

}  // namespace
