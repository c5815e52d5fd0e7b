#include "haptic/kinesthetic/port_safety.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "haptic/kinesthetic/study.hpp"

namespace haptic::kinesthetic {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// Done when (partly met): with the passivity controller on, the net energy the device
// generates over pumping cycles is <= 0; with it off, it is > 0. Closed loops inside the wall,
// the user circling in the direction that the non-conservative field (§5.7.2, §6.9) feeds;
// the port has the exoskeleton's 500 N/s rate limit. Measured (5 loops, README): with the
// controller on the net is <= 0 (to rounding) in 6 of the 9 strategy/angle cases of the
// study; naive at 60 deg and anisotropic at 30 and 45 deg keep 0.3-1 % of the uncontrolled
// energy, lost in one-tick velocity reversals near first contact that the controller cannot
// predict. The bound below is
// what is actually guaranteed today; see README "Kinesthetic rendering".
TEST(PassivityController, StopsEnergyPumpingInsideTheWall) {
    // linearized_subspace renders exactly like subspace on one wall, so it is left out here.
    for (const auto method :
         {RenderingMethod::kNaive, RenderingMethod::kSubspace, RenderingMethod::kAnisotropic}) {
        for (const double beta_deg : {30.0, 60.0}) {
            study::PumpingCase pumping;
            pumping.wall.beta_rad = beta_deg * kDeg;
            pumping.cycles = 2;
            const auto off =
                study::runEnergyPumping(pumping, method, RhoMode::kClosedForm, 0.0, false);
            const auto on =
                study::runEnergyPumping(pumping, method, RhoMode::kClosedForm, 0.0, true);
            EXPECT_GT(off.generated_energy_j, 1e-4)
                << static_cast<int>(method) << " beta " << beta_deg;
            EXPECT_LT(on.generated_energy_j, 0.02 * off.generated_energy_j)
                << static_cast<int>(method) << " beta " << beta_deg;
            EXPECT_GT(on.max_force_n, 0.5 * off.max_force_n);
        }
    }
}

TEST(PassivityController, TheOtherCirculationAbsorbsEnergyAndIsLeftAlone) {
    study::PumpingCase pumping;
    pumping.wall.beta_rad = 45 * kDeg;
    pumping.clockwise = true;
    pumping.cycles = 2;
    const auto off =
        study::runEnergyPumping(pumping, RenderingMethod::kNaive, RhoMode::kManual, 1.0, false);
    EXPECT_LT(off.generated_energy_j, 0.0);
}

TEST(PassivityController, AccountsZeroOrderHoldEnergy) {
    PassivityController sut(1e-3, 100.0);
    sut.setEnabled(false);
    sut.observe(0.0);
    sut.record(2.0);     // 2 N held along +ell
    sut.observe(0.001);  // moved 1 mm with it: the device gave 2 mJ
    EXPECT_NEAR(sut.observedEnergy(), -2e-3, 1e-15);
    EXPECT_DOUBLE_EQ(sut.correct(1.0), 1.0);  // disabled: untouched
    sut.setEnabled(true);
    // Still moving at 1 m/s: the correction must oppose the motion.
    EXPECT_LT(sut.correct(1.0), 1.0);
}

TEST(SaturateForce, ClampsMagnitudeThenRate) {
    EXPECT_DOUBLE_EQ(saturateForce(50.0, 0.0, 10.0, 1e6, 1e-3), 10.0);
    EXPECT_DOUBLE_EQ(saturateForce(10.0, 0.0, 20.0, 500.0, 1e-3), 0.5);
    EXPECT_DOUBLE_EQ(saturateForce(-10.0, 0.2, 20.0, 500.0, 1e-3), -0.3);
}

PortGuardConfig guardConfig() {
    PortGuardConfig c;
    c.max_force_n = 10.0;
    c.max_force_rate_n_per_s = 1e5;
    c.fade_time_s = 0.01;  // 10 ticks
    c.passivity_enabled = false;
    return c;
}

TEST(ActuatorPortGuard, FadesInFadesOutOnStaleInputAndNeverSteps) {
    ActuatorPortGuard sut(guardConfig());
    double previous = 0.0;
    for (int k = 0; k < 10; ++k) {
        const auto command = sut.apply(5.0, 0.0, true);
        EXPECT_LE(std::abs(command.force_n - previous), 0.5 + 1e-12);
        previous = command.force_n;
    }
    EXPECT_NEAR(previous, 5.0, 1e-12);
    for (int k = 0; k < 10; ++k) {
        const auto command = sut.apply(5.0, 0.0, false);
        EXPECT_TRUE(command.flags & kPortStale);
        EXPECT_LE(std::abs(command.force_n - previous), 0.5 + 1e-12);
        previous = command.force_n;
    }
    EXPECT_NEAR(previous, 0.0, 1e-12);
}

TEST(ActuatorPortGuard, RejectsNaNAndSaturates) {
    ActuatorPortGuard sut(guardConfig());
    for (int k = 0; k < 20; ++k) {
        (void)sut.apply(50.0, 0.0, true);
    }
    auto command = sut.apply(50.0, 0.0, true);
    EXPECT_DOUBLE_EQ(command.force_n, 10.0);
    EXPECT_TRUE(command.flags & kPortForceSaturated);
    command = sut.apply(std::numeric_limits<double>::quiet_NaN(), 0.0, true);
    EXPECT_TRUE(command.flags & kPortNonFiniteCommand);
    EXPECT_TRUE(std::isfinite(command.force_n));
    EXPECT_NEAR(command.force_n, 9.0, 1e-12);  // holding the last good force, fading
    command = sut.apply(1.0, std::numeric_limits<double>::infinity(), true);
    EXPECT_TRUE(command.flags & kPortNonFinitePosition);
    EXPECT_NEAR(command.force_n, 8.0, 1e-12);
    EXPECT_STREQ(describePortFlag(kPortNonFiniteCommand), "rendered force is NaN/Inf, fading out");

    PortGuardConfig bad = guardConfig();
    bad.max_force_n = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(ActuatorPortGuard{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace haptic::kinesthetic
