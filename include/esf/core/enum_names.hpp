#pragma once
// One name table per enum: the names that files, the command line and Python use for its
// values are spelled once, beside the enum, and to_string(), parse_enum() and enum_names() read
// them from there. An enum gets its table by specialising EnumNames:
//
//   enum class SensorNoise { kNone, kKinect };
//   template <>
//   struct EnumNames<SensorNoise> {
//       static constexpr const char* what = "sensor noise";  // names the enum in errors
//       static constexpr std::array<EnumName<SensorNoise>, 2> table{
//           {{SensorNoise::kNone, "none"}, {SensorNoise::kKinect, "kinect"}}};
//   };

#include <array>
#include <concepts>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace esf {

/// One value of an enum and its name.
template <typename Enum>
struct EnumName {
    Enum value;
    const char* name;
};

/// Specialised for each named enum with `what` (the enum in words) and `table` (every value
/// once, in the order choices are listed).
template <typename Enum>
struct EnumNames;

template <typename Enum>
concept NamedEnum = requires {
    { EnumNames<Enum>::what } -> std::convertible_to<const char*>;
    EnumNames<Enum>::table.size();
};

/// The name of `value`; "unknown" for a value outside the table (a cast from a bad number).
template <NamedEnum Enum>
constexpr const char* to_string(Enum value) {
    for (const EnumName<Enum>& entry : EnumNames<Enum>::table)
        if (entry.value == value) return entry.name;
    return "unknown";
}

/// Every name, in table order.
template <NamedEnum Enum>
std::vector<std::string> enum_names() {
    std::vector<std::string> names;
    names.reserve(EnumNames<Enum>::table.size());
    for (const EnumName<Enum>& entry : EnumNames<Enum>::table) names.emplace_back(entry.name);
    return names;
}

/// The names joined by `separator` ("none|kinect" with "|").
template <NamedEnum Enum>
std::string enum_choices(std::string_view separator) {
    std::string text;
    for (const EnumName<Enum>& entry : EnumNames<Enum>::table) {
        if (!text.empty()) text += separator;
        text += entry.name;
    }
    return text;
}

/// The value named `name`; throws std::invalid_argument naming it and the choices otherwise:
/// "unknown sensor noise 'kinect2' (expected none or kinect)".
template <NamedEnum Enum>
Enum parse_enum(std::string_view name) {
    for (const EnumName<Enum>& entry : EnumNames<Enum>::table)
        if (name == entry.name) return entry.value;
    const auto& table = EnumNames<Enum>::table;
    std::string choices;
    for (std::size_t i = 0; i < table.size(); ++i) {
        if (i > 0) choices += i + 1 == table.size() ? " or " : ", ";
        choices += table[i].name;
    }
    throw std::invalid_argument("unknown " + std::string(EnumNames<Enum>::what) + " '" +
                                std::string(name) + "' (expected " + choices + ")");
}

}  // namespace esf
