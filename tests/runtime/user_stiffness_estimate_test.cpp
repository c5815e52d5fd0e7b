// The online estimate of the user's stiffness (rendering.user_stiffness_estimate) in hapticd's
// exoskeleton channel, against the emulated finger of the virtual user (config/user.yaml's
// hand impedance, scaled) whose stiffness is known: a press into a wall with anisotropic
// rendering, the estimate within 1 s of contact, and the ghost force with the estimated rho*
// against the one with the true k_u configured.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

#include "haptic/config/virtual_user.hpp"
#include "haptic/emu/device_models.hpp"
#include "haptic/kinesthetic/device_model.hpp"
#include "haptic/runtime/exoskeleton_channel.hpp"
#include "runtime_rig.hpp"

namespace haptic::testing {
namespace {

constexpr std::array<double, 3> kStartPose{0.35, 0.45, 0.30};
// The wall limits flexion along s(q) = q_mcp + q_dip, just beyond the start: a normal with a
// large share outside the actuated direction, where rho decides the force.
constexpr std::array<double, 3> kWallNormal{-1.0, 0.0, -1.0};
constexpr double kWallMarginRad = 0.02;
// The intent presses on past the wall: this much further in every joint, over kPressS.
constexpr std::array<double, 3> kPress{0.05, 0.05, 0.025};
constexpr double kPressS = 0.4;

double wallCoordinate(const std::array<double, 3>& q) {
    return -(kWallNormal[0] * q[0] + kWallNormal[1] * q[1] + kWallNormal[2] * q[2]);
}

config::HandImpedanceConfig shippedHand() {
    return config::loadVirtualUserConfig(std::string(HAPTIC_CONFIG_DIR) + "/user.yaml")
        .hand_impedance;
}

// k_u of an isotropic user that the actuator would feel as this finger: |B|^2 / B^T K^-1 B.
double equivalentUserStiffness(const config::DeviceConfig& device,
                               const config::HandImpedanceConfig& hand,
                               const std::array<double, 3>& q) {
    const kinesthetic::ExoskeletonDevice model(device.exoskeleton());
    kinesthetic::ConfigVector q_vector(3);
    q_vector << q[0], q[1], q[2];
    kinesthetic::ActuationMatrix B;
    model.actuationMatrix(q_vector, B);
    double compliance = 0.0;
    for (int j = 0; j < 3; ++j) {
        compliance += B(j, 0) * B(j, 0) / hand.stiffness_nm_per_rad[static_cast<std::size_t>(j)];
    }
    return B.col(0).squaredNorm() / compliance;
}

struct PressSetup {
    double stiffness_scale{1.0};  // of config/user.yaml's finger
    bool estimate{true};          // else configured_k_u is the renderer's k_u
    double configured_k_u{0.6};
    double probe_amplitude_m{25e-6};
    double probe_frequency_hz{5.0};
    double probe_time_s{1.5};
    const char* method{"anisotropic"};
    bool enable{true};
};

struct PressRun {
    double true_k_u{0.0};              // at the pose of contact
    double estimate_at_1s{0.0};        // NaN if none was valid by then
    double worst_error_after_1s{0.0};  // |estimate / true - 1| over every tick after 1 s
    double ghost_rms_nm{0.0};          // |ghost torque| over the contact
    double force_mean_n{0.0};          // commanded, over the contact
    double applied_k_u_end{0.0};       // the renderer's k_u at the end
    double chatter_n{0.0};             // RMS of the measured force minus its 33-tick moving average
    int contact_ticks{0};
    double response_m{0.0};  // the estimator's, at the end
    double estimate_end{0.0};
    double probe_energy_j{0.0};
    int passivity_ticks{0};    // contact ticks in which the passivity controller cut the force
    std::vector<double> felt;  // the measured force over the contact, one per tick
};

PressRun press(const PressSetup& setup) {
    config::HandImpedanceConfig hand = shippedHand();
    for (double& k : hand.stiffness_nm_per_rad) {
        k *= setup.stiffness_scale;
    }
    RuntimeRig rig([&](std::vector<config::DeviceConfig>& devices) {
        auto& rendering = std::get<config::ExoskeletonConfig>(devices[kExo].params).rendering;
        rendering.method = config::RenderingMethod::kAnisotropic;
        rendering.user_stiffness_estimate.enabled = setup.estimate;
        rendering.user_stiffness_estimate.probe_amplitude_m = setup.probe_amplitude_m;
        rendering.user_stiffness_estimate.probe_frequency_hz = setup.probe_frequency_hz;
        rendering.user_stiffness_estimate.probe_time_s = setup.probe_time_s;
        if (!setup.estimate) {
            rendering.user_stiffness_nm_per_rad = setup.configured_k_u;
        }
    });
    emu::ExoskeletonModel& finger = *rig.emulators[kExo]->exoskeletonModel();
    finger.setHandImpedance(hand);
    finger.placeFinger(kStartPose);
    finger.setIntent(kStartPose);

    msgs::LinearConstraint& wall = rig.constraint_set.constraints[0];
    wall.a = {kWallNormal[0], kWallNormal[1], kWallNormal[2]};
    wall.b = -(wallCoordinate(kStartPose) + kWallMarginRad);
    // The reference's direction is the wall's normal: everything felt across it is ghost.
    rig.constraint_set.reference_torque_nm = {kWallNormal[0], kWallNormal[1], kWallNormal[2]};
    rig.offerContact();
    rig.ticks(20);
    EXPECT_TRUE(rig.command(msgs::CommandKind::kSetMethod, setup.method));
    if (setup.enable) {
        EXPECT_TRUE(rig.command(msgs::CommandKind::kEnable));
    }
    const auto& channel = static_cast<runtime::ExoskeletonChannel&>(rig.runtime.channel(kExo));

    PressRun run;
    run.estimate_at_1s = std::nan("");
    int contact_start = -1;
    std::vector<double>& felt = run.felt;
    double ghost_squared = 0.0;
    double force_sum = 0.0;
    const int press_start = 300;  // after the 100 ms fade-in
    for (int i = 0; i < 3500; ++i) {
        if (i % 10 == 0) {
            rig.offerContact();  // a 100 Hz sim
        }
        const double t_press = std::clamp((i - press_start) * 1e-3 / kPressS, 0.0, 1.0);
        std::array<double, 3> intent{};
        for (std::size_t j = 0; j < 3; ++j) {
            intent[j] = kStartPose[j] + t_press * kPress[j];
        }
        finger.setIntent(intent);
        rig.tick();
        if (!channel.renderOutput().in_contact) {
            continue;
        }
        if (contact_start < 0) {
            contact_start = i;
            run.true_k_u = equivalentUserStiffness(rig.devices[kExo], hand, finger.jointRad());
        }
        ++run.contact_ticks;
        const auto& ghost = rig.core.deviceReport(kExo).exoskeleton.ghost_torque_nm;
        ghost_squared += ghost[0] * ghost[0] + ghost[1] * ghost[1] + ghost[2] * ghost[2];
        force_sum += rig.exoForce();
        felt.push_back(rig.core.deviceReport(kExo).actuator_force[0]);
        run.passivity_ticks += (channel.portFlags() & kinesthetic::kPortPassivityActive) != 0;
        if (const auto* estimator = channel.userStiffnessEstimator()) {
            if (i - contact_start >= 1000) {
                const double error = estimator->valid()
                                         ? std::abs(estimator->stiffness() / run.true_k_u - 1.0)
                                         : std::numeric_limits<double>::infinity();
                run.worst_error_after_1s = std::max(run.worst_error_after_1s, error);
            }
            if (i - contact_start == 1000 && estimator->valid()) {
                run.estimate_at_1s = estimator->stiffness();
            }
        }
    }
    run.ghost_rms_nm = std::sqrt(ghost_squared / std::max(run.contact_ticks, 1));
    run.force_mean_n = force_sum / std::max(run.contact_ticks, 1);
    run.applied_k_u_end = channel.userStiffness();
    run.probe_energy_j = channel.probeEnergy();
    if (const auto* estimator = channel.userStiffnessEstimator()) {
        run.response_m = estimator->responseAmplitude();
        run.estimate_end = estimator->stiffness();
    }
    double chatter_squared = 0.0;
    int chatter_count = 0;
    for (std::size_t i = 16; i + 16 < felt.size(); ++i) {
        double mean = 0.0;
        for (std::size_t j = i - 16; j <= i + 16; ++j) {
            mean += felt[j] / 33.0;
        }
        chatter_squared += (felt[i] - mean) * (felt[i] - mean);
        ++chatter_count;
    }
    run.chatter_n = std::sqrt(chatter_squared / std::max(chatter_count, 1));
    return run;
}

double lastSecondMean(const std::vector<double>& signal) {
    double sum = 0.0;
    for (std::size_t i = signal.size() - 1000; i < signal.size(); ++i) {
        sum += signal[i];
    }
    return sum / 1000.0;
}

// Amplitude of `signal` at `frequency_hz` (one sample per ms), over its last second, mean
// removed.
double amplitudeAt(const std::vector<double>& signal, double frequency_hz) {
    double re = 0.0;
    double im = 0.0;
    const std::size_t start = signal.size() - 1000;
    double mean = 0.0;
    for (std::size_t i = start; i < signal.size(); ++i) {
        mean += signal[i] / 1000.0;
    }
    for (std::size_t i = start; i < signal.size(); ++i) {
        const double phase = 2.0 * std::numbers::pi * frequency_hz * static_cast<double>(i) * 1e-3;
        re += (signal[i] - mean) * std::cos(phase);
        im += (signal[i] - mean) * std::sin(phase);
    }
    return 2.0 * std::hypot(re, im) / static_cast<double>(signal.size() - start);
}

TEST(UserStiffnessEstimate, ConvergesWithinFifteenPercentOfTheVirtualUsersWithinOneSecond) {
    for (const double scale : {0.5, 1.0, 2.0}) {
        const PressRun estimated = press({.stiffness_scale = scale});
        const PressRun exact = press(
            {.stiffness_scale = scale, .estimate = false, .configured_k_u = estimated.true_k_u});
        // What the configured prior (the shipped 0.6 N m/rad) would have rendered instead.
        const PressRun prior = press({.stiffness_scale = scale, .estimate = false});
        std::printf(
            "user x%.1f: true k_u %.3f N m/rad, estimate at 1 s %.3f (%+.1f %%), worst "
            "after 1 s %.1f %%, renderer's k_u at the end %.3f; ghost RMS %.4f N m "
            "estimated vs %.4f N m true (%+.1f %%); mean force %.2f vs %.2f N; %d contact "
            "ticks; chatter %.3f vs %.3f N; with the prior k_u: ghost RMS %.4f N m; last second's "
            "mean force %.3f vs %.3f N; the probe gave the finger %.2f mJ; passivity "
            "cut %d vs %d ticks\n",
            scale, estimated.true_k_u, estimated.estimate_at_1s,
            100.0 * (estimated.estimate_at_1s / estimated.true_k_u - 1.0),
            100.0 * estimated.worst_error_after_1s, estimated.applied_k_u_end,
            estimated.ghost_rms_nm, exact.ghost_rms_nm,
            100.0 * (estimated.ghost_rms_nm / exact.ghost_rms_nm - 1.0), estimated.force_mean_n,
            exact.force_mean_n, estimated.contact_ticks, estimated.chatter_n, exact.chatter_n,
            prior.ghost_rms_nm, lastSecondMean(estimated.felt), lastSecondMean(exact.felt),
            1e3 * estimated.probe_energy_j, estimated.passivity_ticks, exact.passivity_ticks);
        ASSERT_GT(estimated.contact_ticks, 2000) << "the press holds the wall";
        EXPECT_NEAR(estimated.estimate_at_1s, estimated.true_k_u, 0.15 * estimated.true_k_u)
            << "user x" << scale;
        EXPECT_LE(estimated.worst_error_after_1s, 0.15) << "and it stays there";
        EXPECT_LE(estimated.ghost_rms_nm, 1.10 * exact.ghost_rms_nm) << "user x" << scale;
        // The renderer's k_u is the estimate, and that is what made the difference: the prior
        // is off by a third or more for every one of these users.
        EXPECT_NEAR(estimated.applied_k_u_end, estimated.estimate_end,
                    0.02 * estimated.estimate_end);
        EXPECT_NEAR(estimated.applied_k_u_end, estimated.true_k_u, 0.15 * estimated.true_k_u);
        EXPECT_GT(std::abs(0.6 / estimated.true_k_u - 1.0), 0.3);
        // The probe is booked as a source outside the rendering: it never makes the passivity
        // controller soften the wall, and once it stops the wall is the true k_u's.
        EXPECT_LE(estimated.passivity_ticks, exact.passivity_ticks + 10) << "user x" << scale;
        EXPECT_NEAR(lastSecondMean(estimated.felt), lastSecondMean(exact.felt),
                    0.05 * std::abs(lastSecondMean(exact.felt)))
            << "user x" << scale;
    }
}

// probe_amplitude_m sets how far the probe moves the finger, probe_frequency_hz at what rate
// (the felt force ripples at that frequency and twice it, not at the other setting's), and
// probe_time_s for how long: after it the ripple is gone and the estimate holds.
TEST(UserStiffnessEstimate, TheProbeKeysSetItsExcursionTonesAndDuration) {
    const PressRun whole = press({.probe_time_s = 60.0});
    const PressRun half = press({.probe_amplitude_m = 12.5e-6, .probe_time_s = 60.0});
    ASSERT_GT(whole.response_m, 0.0);
    EXPECT_NEAR(half.response_m / whole.response_m, 0.5, 0.1);
    EXPECT_NEAR(half.estimate_end, whole.true_k_u, 0.15 * whole.true_k_u)
        << "half the excursion still reads the finger";
    const PressRun slower = press({.probe_frequency_hz = 3.0, .probe_time_s = 60.0});
    EXPECT_GT(amplitudeAt(whole.felt, 5.0), 5.0 * amplitudeAt(whole.felt, 3.0));
    EXPECT_GT(amplitudeAt(slower.felt, 3.0), 5.0 * amplitudeAt(slower.felt, 5.0));
    EXPECT_GT(amplitudeAt(slower.felt, 6.0), 5.0 * amplitudeAt(slower.felt, 5.0));
    EXPECT_NEAR(slower.estimate_end, slower.true_k_u, 0.15 * slower.true_k_u);
    const PressRun shipped = press({});  // probes the first 1.5 s of the 2.6 s contact
    EXPECT_LT(amplitudeAt(shipped.felt, 5.0), 0.1 * amplitudeAt(whole.felt, 5.0));
    EXPECT_NEAR(shipped.estimate_end, shipped.true_k_u, 0.15 * shipped.true_k_u) << "it holds";
    std::printf(
        "response %.1f um (25 um probe), %.1f um (12.5 um); felt ripple at 5/10 Hz %.3f/"
        "%.3f N (mean force %.2f N), at 3/6 Hz with the 3 Hz probe %.3f/%.3f N; over the "
        "last second with the 1.5 s probe time %.3f N at 5 Hz\n",
        whole.response_m * 1e6, half.response_m * 1e6, amplitudeAt(whole.felt, 5.0),
        amplitudeAt(whole.felt, 10.0), whole.force_mean_n, amplitudeAt(slower.felt, 3.0),
        amplitudeAt(slower.felt, 6.0), amplitudeAt(shipped.felt, 5.0));
}

// The probe serves the method that uses k_u and a finger the port really pushes: with
// linearized_subspace, or with the port never enabled (the renderer in contact, nothing
// sent), nothing ripples and k_u stays the prior.
TEST(UserStiffnessEstimate, OnlyAnisotropicWithTheDeviceEnabledIsProbed) {
    for (const PressSetup setup :
         {PressSetup{.method = "linearized_subspace"}, PressSetup{.enable = false}}) {
        const PressRun run = press(setup);
        ASSERT_GT(run.contact_ticks, 1000) << setup.method << " " << setup.enable;
        EXPECT_TRUE(std::isnan(run.estimate_end)) << setup.method << " " << setup.enable;
        EXPECT_DOUBLE_EQ(run.applied_k_u_end, 0.6);
        EXPECT_EQ(run.probe_energy_j, 0.0);
    }
    const PressRun idle = press({.enable = false});
    for (double f : idle.felt) {
        ASSERT_EQ(f, 0.0) << "a disabled port sends nothing, the probe included";
    }
}

}  // namespace
}  // namespace haptic::testing
