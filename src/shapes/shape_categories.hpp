#pragma once
// The parametric categories of the shape generator. Each builder draws its parameters from
// `rng` and returns the shape's closed components in metres, +z up (placement on z = 0 and
// centring are left to the caller).

#include "shapes/shape_primitives.hpp"

namespace esf::shapes {

Surface make_apple(Rng& rng);
Surface make_banana(Rng& rng);
Surface make_bottle(Rng& rng);
Surface make_bowl(Rng& rng);
Surface make_can(Rng& rng);
Surface make_car(Rng& rng);
Surface make_donut(Rng& rng);
Surface make_hammer(Rng& rng);
Surface make_mug(Rng& rng);
Surface make_tetra_pak(Rng& rng);
Surface make_toilet_paper(Rng& rng);

}  // namespace esf::shapes
