#pragma once
// Tests of the PCL baseline descriptors skip, saying why, in a build without the baselines
// module (-DESF_WITH_PCL=OFF); everything else must work there.

#include <gtest/gtest.h>

#include "esf/descriptors/descriptor.hpp"

#define ESF_REQUIRE_BASELINES()                                                            \
    do {                                                                                   \
        if (!esf::descriptor_available("vfh"))                                             \
            GTEST_SKIP() << "this build has no PCL baselines module (-DESF_WITH_PCL=OFF)"; \
    } while (false)
