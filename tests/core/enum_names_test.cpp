#include "esf/core/enum_names.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace esf {

enum class Fruit { kApple, kPear, kPlum };

template <>
struct EnumNames<Fruit> {
    static constexpr const char* what = "fruit";
    static constexpr std::array<EnumName<Fruit>, 3> table{
        {{Fruit::kPear, "pear"}, {Fruit::kApple, "apple"}, {Fruit::kPlum, "plum"}}};
};

}  // namespace esf

namespace {

using esf::Fruit;

TEST(EnumNames, NamesEveryValueFromTheTable) {
    static_assert(esf::to_string(Fruit::kPlum)[0] == 'p');
    EXPECT_STREQ(esf::to_string(Fruit::kApple), "apple");
    EXPECT_STREQ(esf::to_string(static_cast<Fruit>(7)), "unknown");
    EXPECT_EQ(esf::enum_names<Fruit>(), (std::vector<std::string>{"pear", "apple", "plum"}));
    EXPECT_EQ(esf::enum_choices<Fruit>("|"), "pear|apple|plum");
}

TEST(EnumNames, ParsesNamesAndRefusesOthersByName) {
    for (const std::string& name : esf::enum_names<Fruit>())
        EXPECT_EQ(esf::to_string(esf::parse_enum<Fruit>(name)), name);
    try {
        esf::parse_enum<Fruit>("Pear");
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "unknown fruit 'Pear' (expected pear, apple or plum)");
    }
}

}  // namespace
