// The accuracy targets that need fine meshes: linear tetrahedra converge slowly in bending
// and under a contact patch. Minutes under ASan, so Release only, labelled softhand_fine:
//   ctest --test-dir build/release -L softhand_fine

#include <gtest/gtest.h>

#include "validation_support.hpp"

namespace haptic::softhand {
namespace {

TEST(SofthandFine, HertzWithinTenPercentAtSmallIndentation) {
    for (double indentation : {0.2e-3, 0.3e-3, 0.4e-3}) {
        EXPECT_NEAR(hertzForceRatio(16, 1.25, 0.04, indentation), 1.0, 0.10)
            << "indentation " << indentation;
    }
}

TEST(SofthandFine, CantileverWithinFivePercentOfEulerBernoulli) {
    EXPECT_NEAR(cantileverTipDeflectionRatio({CANTILEVER_FINE_CELLS}), 1.0, 0.05);
}

}  // namespace
}  // namespace haptic::softhand
