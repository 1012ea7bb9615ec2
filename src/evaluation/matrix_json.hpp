#pragma once
// A 4 x 4 pose as JSON: 16 numbers, row-major (truth.json, scene reports).

#include <nlohmann/json.hpp>

namespace esf::detail {

template <class Matrix>
nlohmann::json row_major_json(const Matrix& m) {
    nlohmann::json out = nlohmann::json::array();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out.push_back(m(r, c));
    return out;
}

}  // namespace esf::detail
