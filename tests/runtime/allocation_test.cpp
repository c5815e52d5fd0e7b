// hapticd's full per-tick path (both devices, real drivers, renderers, safety stages and
// DaemonCore, the emulators answering on the loopback bus) must not touch the heap after
// start.

#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "runtime_rig.hpp"

namespace haptic::testing {
namespace {

TEST(RuntimeAllocation, TenThousandTicksOfBothDevicesAllocateNothing) {
    RuntimeRig rig;
    rig.offerContact();
    rig.ticks(20);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    rig.ticks(5);

    std::uint64_t allocations = 0;
    double peak_force = 0.0;
    {
        ScopedAllocationCounter counter;
        for (int i = 0; i < 10'000; ++i) {
            if (i % 10 == 0) {
                rig.offerContact();  // a 100 Hz sim
            }
            if (i == 5'000) {
                (void)rig.command(msgs::CommandKind::kDisable);
                (void)rig.command(msgs::CommandKind::kSetMethod, "anisotropic");
                (void)rig.command(msgs::CommandKind::kEnable);
            }
            rig.tick();
            peak_force = std::max(peak_force, std::abs(rig.exoForce()));
        }
        allocations = counter.allocations();
    }
    EXPECT_EQ(allocations, 0U);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kRendering);
    EXPECT_GT(peak_force, 1.0) << "the loop must have rendered force, not idled";
    EXPECT_GT(rig.core.deviceReport(kExo).can.rx_frames, 10'000U);
}

}  // namespace
}  // namespace haptic::testing
