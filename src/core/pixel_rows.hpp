#pragma once
// Internal: image rows and columns of pixel indices (row-major, `width` pixels a row) with one
// integer division per change of row instead of one per pixel: segmentation visits the pixels
// of a frame in ascending order, so most lookups stay in the current row.

#include <cstdint>

namespace esf::detail {

class PixelRows {
  public:
    explicit PixelRows(std::uint32_t width) : width_(width) {}

    /// Moves to `pixel` (any order; ascending is fastest).
    void seek(std::uint32_t pixel) {
        if (pixel < start_ || pixel - start_ >= width_) {
            row_ = pixel / width_;
            start_ = row_ * width_;
        }
        col_ = pixel - start_;
    }
    std::uint32_t row() const { return row_; }
    std::uint32_t col() const { return col_; }

  private:
    std::uint32_t width_;
    std::uint32_t row_ = 0, col_ = 0;
    std::uint32_t start_ = 0;  // first pixel of row_
};

}  // namespace esf::detail
