// The exoskeleton's safety keys that act in hapticd's channel, each changed from the shipped
// value and its effect read off the channel and the emulated device: the stiffness clamp
// (safety.max_stiffness_n_per_m), the velocity fade (safety.max_velocity_m_per_s), the force
// cap, its rate limit and the fade on a stale device state (max_force_n,
// max_force_rate_n_per_s, fade_out_ms), and rendering.max_constraints. The
// clamp's value is also what the configuration's passivity margin is checked for
// (config_test's ConfigPassivityMargin).

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>

#include "haptic/runtime/exoskeleton_channel.hpp"
#include "runtime_rig.hpp"

namespace haptic::testing {
namespace {

const runtime::ExoskeletonChannel& exoChannel(RuntimeRig& rig) {
    return static_cast<runtime::ExoskeletonChannel&>(rig.runtime.channel(kExo));
}

// A wall `depth_rad` inside the emulated finger's current pose, re-placed at the sim's 100 Hz
// as the finger follows its own sine, so the renderer always has a shallow contact.
void placeWall(RuntimeRig& rig, double depth_rad) {
    const auto& q = rig.core.deviceReport(kExo).joint_position_rad;
    msgs::LinearConstraint& wall = rig.constraint_set.constraints[0];
    wall.a = {-1.0, -0.5, 0.0};
    wall.b = -(q[0] + 0.5 * q[1]) + depth_rad;
    rig.offerContact();
}

std::unique_ptr<RuntimeRig> exoRig(double max_stiffness_n_per_m, double max_velocity_m_per_s) {
    return std::make_unique<RuntimeRig>([=](std::vector<config::DeviceConfig>& devices) {
        devices[kExo].safety.max_stiffness_n_per_m = max_stiffness_n_per_m;
        devices[kExo].safety.max_velocity_m_per_s = max_velocity_m_per_s;
        // Without the rendered damping the actuator force is the spring alone.
        std::get<config::ExoskeletonConfig>(devices[kExo].params)
            .rendering.actuator_damping_n_s_per_m = 0.0;
    });
}

// rendering.max_constraints: the channel renders the first that many constraints of a set.
// A set whose first constraint the finger keeps and whose second it is always inside: with
// the shipped 8 the wall pushes, with 1 only the kept constraint is seen and nothing does.
TEST(ExoskeletonRenderingKeys, OnlyTheFirstMaxConstraintsOfASetAreRendered) {
    for (const int max_constraints : {8, 1}) {
        RuntimeRig rig([=](std::vector<config::DeviceConfig>& devices) {
            std::get<config::ExoskeletonConfig>(devices[kExo].params).rendering.max_constraints =
                max_constraints;
        });
        msgs::LinearConstraint kept;  // q_MCP <= 10 rad: never reached
        kept.a = {-1.0, 0.0, 0.0};
        kept.b = -10.0;
        const msgs::LinearConstraint wall = rig.constraint_set.constraints[0];
        rig.constraint_set.constraints.clear();
        rig.constraint_set.constraints.push_back(kept);
        rig.constraint_set.constraints.push_back(wall);
        rig.offerContact();
        rig.ticks(20);
        ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
        double largest_n = 0.0;
        for (int i = 0; i < 300; ++i) {
            if (i % 10 == 0) {
                rig.offerContact();
            }
            rig.tick();
            largest_n = std::max(largest_n, std::abs(rig.exoForce()));
        }
        ASSERT_EQ(rig.core.state(), msgs::DaemonState::kRendering) << max_constraints;
        if (max_constraints == 8) {
            EXPECT_GT(largest_n, 1.0);
        } else {
            EXPECT_EQ(largest_n, 0.0);
        }
    }
}

// The shipped 15 kN/m, and half of it. The rigs stay IDLE (nothing is sent), so both emulated
// fingers move alike and the renderers see the same poses.
TEST(ExoskeletonSafetyKeys, TheCouplingAlongTheActuatorIsClampedToMaxStiffness) {
    const double shipped = 15000.0;
    auto rig = exoRig(shipped, 0.05);
    auto half = exoRig(0.5 * shipped, 0.05);
    int clamped_in_both = 0;
    for (int i = 0; i < 2000; ++i) {
        for (RuntimeRig* r : {rig.get(), half.get()}) {
            if (i % 10 == 0) {
                placeWall(*r, 0.01);
            }
            r->tick();
        }
        const auto& channel = exoChannel(*rig);
        const auto& halved = exoChannel(*half);
        if (i < 20 || !channel.renderOutput().in_contact) {
            continue;
        }
        ASSERT_LE(channel.actuatorStiffness(), shipped * (1.0 + 1e-12)) << "tick " << i;
        ASSERT_LE(halved.actuatorStiffness(), 0.5 * shipped * (1.0 + 1e-12)) << "tick " << i;
        const bool clamped = (channel.portFlags() & kinesthetic::kPortStiffnessLimited) != 0;
        if (clamped) {
            EXPECT_NEAR(channel.actuatorStiffness(), shipped, 1e-9 * shipped) << "tick " << i;
            // Clamped in both: the same pose and wall give half the force.
            ++clamped_in_both;
            EXPECT_NEAR(halved.renderOutput().actuator_force[0],
                        0.5 * channel.renderOutput().actuator_force[0],
                        1e-9 * (1.0 + std::abs(channel.renderOutput().actuator_force[0])))
                << "tick " << i;
        }
    }
    // With the shipped k_a (2 N m/rad) the coupling along the actuator is 15.5 kN/m at the
    // most extended pose and far more when flexed: the clamp acts on every pose the finger
    // sweeps.
    EXPECT_GT(clamped_in_both, 1000);
}

// A limit a few mm/s: the emulated finger's own sine moves the rod faster than that in its
// middle and slower near its turning points, against a wall 0.03 rad in, for 3000 ticks. On
// every tick where a force would drive the rod along its motion at twice the limit or more,
// the force sent is 0. With `switch_methods` the method changes every 150 ticks, so every tick
// lies inside a switch's bumpless window (200 ticks).
struct FadeRun {
    int driving_fast{0};    // ticks faded to zero
    int resisting_fast{0};  // fast ticks whose force resists the motion (kept)
    int slow_pushing{0};    // slow ticks with force: it returns when the rod slows down
};

FadeRun renderAgainstTheVelocityLimit(bool switch_methods) {
    const double limit = 0.004;
    auto rig = exoRig(15000.0, limit);
    rig->offerContact();
    rig->ticks(20);
    EXPECT_TRUE(rig->command(msgs::CommandKind::kEnable));
    const std::array<const char*, 6> methods{"standard", "naive",       "nullspace",
                                             "subspace", "anisotropic", "linearized_subspace"};
    FadeRun run;
    for (int i = 0; i < 3000; ++i) {
        if (switch_methods && i % 150 == 0) {
            EXPECT_TRUE(rig->command(msgs::CommandKind::kSetMethod, methods[(i / 150) % 6]));
        }
        if (i % 10 == 0) {
            placeWall(*rig, 0.03);
        }
        rig->tick();
        const auto& channel = exoChannel(*rig);
        if (i < 200 || !channel.renderOutput().in_contact) {
            continue;
        }
        const double rendered_n = channel.renderOutput().actuator_force[0];
        const double velocity = channel.rodVelocity();
        if (!switch_methods) {
            // Inside a switch's window the flag follows the bounded force, not this one.
            const bool limited = (channel.portFlags() & kinesthetic::kPortVelocityLimited) != 0;
            EXPECT_EQ(limited, std::abs(velocity) > limit && rendered_n * velocity > 0.0)
                << "tick " << i;
        }
        if (std::abs(velocity) > 2.0 * limit && rendered_n * velocity > 0.0) {
            ++run.driving_fast;
            EXPECT_EQ(rig->exoForce(), 0.0) << "tick " << i << ", rod at " << velocity << " m/s";
        } else if (std::abs(velocity) > 2.0 * limit && std::abs(rendered_n) > 0.5) {
            ++run.resisting_fast;
        } else if (std::abs(velocity) < 0.5 * limit && std::abs(rig->exoForce()) > 0.1) {
            ++run.slow_pushing;
        }
    }
    EXPECT_EQ(rig->core.state(), msgs::DaemonState::kRendering);
    return run;
}

// A force that drives the rod along its motion fades (to zero at twice the limit) and returns
// when it slows; one that resists the motion is left alone.
TEST(ExoskeletonSafetyKeys, AForceDrivingTheRodFasterThanMaxVelocityFades) {
    const FadeRun run = renderAgainstTheVelocityLimit(false);
    EXPECT_GT(run.driving_fast, 20);
    EXPECT_GT(run.slow_pushing, 50) << "the force returns when the rod slows down";
    std::printf("fast ticks: %d driving (faded), %d resisting (kept)\n", run.driving_fast,
                run.resisting_fast);
}

// The same fade while the method changes: the switch's window bounds how fast the strategy's
// force may move, never the fade. (It was applied after the fade and held a faded force up,
// letting it fall by the 0.5 N rate limit per tick.)
TEST(ExoskeletonSafetyKeys, AMethodSwitchNeverHoldsUpTheVelocityFade) {
    const FadeRun run = renderAgainstTheVelocityLimit(true);
    EXPECT_GT(run.driving_fast, 20);
    EXPECT_GT(run.slow_pushing, 50) << "the force returns when the rod slows down";
}

struct ForceRun {
    double peak_n{0.0};          // the largest force while rendering
    double largest_rise_n{0.0};  // the largest rise of |force| from one tick to the next
    double stale_low_n{0.0};     // the smallest force while the device's state is stale
    int stale_ticks{0};
};

// Renders the rig's saturating contact for 400 ticks, then the exoskeleton's next 40 frames
// are lost (its state goes stale for some tens of ms while its heartbeat timeout is far), then
// the object is taken away.
ForceRun renderThenLoseTheState(RuntimeRig& rig) {
    ForceRun run;
    rig.offerContact();
    rig.ticks(20);
    EXPECT_TRUE(rig.command(msgs::CommandKind::kEnable));
    double previous = rig.exoForce();
    const auto follow = [&] {
        rig.tick();
        run.largest_rise_n =
            std::max(run.largest_rise_n, std::abs(rig.exoForce()) - std::abs(previous));
        previous = rig.exoForce();
    };
    for (int i = 0; i < 400; ++i) {
        if (i % 10 == 0) {
            rig.offerContact();
        }
        follow();
        run.peak_n = std::max(run.peak_n, std::abs(rig.exoForce()));
    }
    rig.emulatorFault(kExo, "drop 40");
    run.stale_low_n = run.peak_n;
    for (int i = 0; i < 100; ++i) {
        if (i % 10 == 0) {
            rig.offerContact();
        }
        follow();
        if ((exoChannel(rig).portFlags() & kinesthetic::kPortStale) != 0) {
            ++run.stale_ticks;
            run.stale_low_n = std::min(run.stale_low_n, std::abs(rig.exoForce()));
        }
    }
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kRendering) << "a short loss is no fault";
    // Back at the cap, then the object is gone at once.
    for (int i = 0; i < 300; ++i) {
        if (i % 10 == 0) {
            rig.offerContact();
        }
        follow();
    }
    EXPECT_NEAR(std::abs(rig.exoForce()), run.peak_n, 1e-9);
    const auto contact = rig.constraint_set.constraints;
    // Within a tick of the sim's message, not at the rate limit (which would take 20 ticks
    // from the cap).
    int zero_from = -1;
    for (int i = 0; i < 100; ++i) {
        if (i % 10 == 0) {
            placeWall(rig, -1.0);
        }
        follow();
        if (rig.exoForce() != 0.0) {
            zero_from = -1;
        } else if (zero_from < 0) {
            zero_from = i;
        }
    }
    EXPECT_EQ(zero_from, 0) << "falling is never slowed";
    // The object back at once: the force rises at the rate limit. The contact only: the
    // header goes on counting, as the sim's does (an old seq would read as a restarted sim).
    rig.constraint_set.constraints = contact;
    for (int i = 0; i < 100; ++i) {
        if (i % 10 == 0) {
            rig.offerContact();
        }
        follow();
    }
    EXPECT_GT(std::abs(rig.exoForce()), 0.3 * run.peak_n) << "the force came back";
    return run;
}

// safety.max_force_n, max_force_rate_n_per_s and fade_out_ms, each changed from the shipped
// value (10 N, 500 N/s, 100 ms to 4 N, 200 N/s, 40 ms): the force saturates at the cap, never
// rises faster than the rate (it may fall at once, the safe direction), and a stale device
// state fades it over fade_out_ms.
TEST(ExoskeletonSafetyKeys, TheForceCapItsRateAndTheStaleStateFadeFollowTheirKeys) {
    const auto rigWith = [](double max_force_n, double rate_n_per_s, int fade_out_ms) {
        return std::make_unique<RuntimeRig>([=](std::vector<config::DeviceConfig>& devices) {
            devices[kExo].safety.max_force_n = max_force_n;
            devices[kExo].safety.max_force_rate_n_per_s = rate_n_per_s;
            devices[kExo].safety.fade_out_ms = fade_out_ms;
        });
    };
    auto shipped_rig = rigWith(10.0, 500.0, 100);
    auto changed_rig = rigWith(4.0, 200.0, 40);
    const ForceRun shipped = renderThenLoseTheState(*shipped_rig);
    const ForceRun changed = renderThenLoseTheState(*changed_rig);
    std::printf(
        "peak %.3f / %.3f N, largest rise %.3f / %.3f N, stale %d / %d ticks, lowest "
        "%.3f / %.3f N\n",
        shipped.peak_n, changed.peak_n, shipped.largest_rise_n, changed.largest_rise_n,
        shipped.stale_ticks, changed.stale_ticks, shipped.stale_low_n, changed.stale_low_n);
    EXPECT_NEAR(shipped.peak_n, 10.0, 1e-9);
    EXPECT_NEAR(changed.peak_n, 4.0, 1e-9);
    EXPECT_NEAR(shipped.largest_rise_n, 0.5, 1e-9) << "the rise runs at the rate limit";
    EXPECT_NEAR(changed.largest_rise_n, 0.2, 1e-9) << "the rise runs at the rate limit";
    // The same stale time takes 100/40 = 2.5 times the share of the force away.
    ASSERT_GT(shipped.stale_ticks, 5);
    EXPECT_EQ(changed.stale_ticks, shipped.stale_ticks);
    const double shipped_share = 1.0 - shipped.stale_low_n / shipped.peak_n;
    const double changed_share = 1.0 - changed.stale_low_n / changed.peak_n;
    EXPECT_GT(shipped_share, 0.02);
    EXPECT_NEAR(changed_share / shipped_share, 2.5, 0.25);
}

}  // namespace
}  // namespace haptic::testing
