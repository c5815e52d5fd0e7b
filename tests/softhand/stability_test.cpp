// Stability at the extremes (issue 5): every case must end finite, with bounded energy, and
// the step report must say what the solver did (clamped, substepped, rejected input).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <tuple>

#include "haptic/softhand/hand_builder.hpp"

namespace haptic::softhand {
namespace {

config::HandConfig fingertipConfig(int resolution) {
    config::HandConfig hand;
    hand.model = config::HandModel::kFingertip;
    hand.finger = config::Finger::kIndex;
    hand.resolution = resolution;
    hand.anthropometry = {0.19, 0.085, 0.016};
    return hand;
}

struct RunSummary {
    bool finite{true};
    double max_abs_energy_j{0.0};
    double max_energy_j{-std::numeric_limits<double>::infinity()};
    double max_distance_m{0.0};
    double final_max_speed_m_per_s{0.0};
    bool any_clamped{false};
    bool any_substepped{false};
    int final_inverted{0};
    int frozen_steps{0};
    int rescaled_steps{0};
    int steps{0};
};

RunSummary run(HandModel& model, int body, double dt, double duration_s,
               const std::function<Vec3(double)>& target) {
    RunSummary out;
    auto& sim = model.simulation;
    const int steps = static_cast<int>(std::ceil(duration_s / dt));
    for (int s = 0; s < steps; ++s) {
        sim.setTrackingTarget(body, target((s + 1) * dt), Mat3::Identity());
        const StepReport report = sim.step(dt);
        out.finite = out.finite && std::isfinite(report.energy_j);
        out.max_abs_energy_j = std::max(out.max_abs_energy_j, std::abs(report.energy_j));
        out.max_energy_j = std::max(out.max_energy_j, report.energy_j);
        out.any_clamped = out.any_clamped || report.clamped;
        out.any_substepped = out.any_substepped || report.substepped;
        out.final_inverted = report.inverted_elements;
        out.frozen_steps += report.zeroed_steps > 0 ? 1 : 0;
        out.rescaled_steps += report.rescaled_steps > 0 ? 1 : 0;
        ++out.steps;
    }
    for (int i = 0; i < sim.nodeCount(); ++i) {
        out.finite = out.finite && sim.nodePosition(i).allFinite();
        out.max_distance_m = std::max(out.max_distance_m, sim.nodePosition(i).norm());
        out.final_max_speed_m_per_s =
            std::max(out.final_max_speed_m_per_s, sim.nodeVelocity(i).norm());
    }
    return out;
}

// Tissue stiffness x contact stiffness x time step: the bone's target presses 6 mm towards a
// table 1 mm below the pad, so the pad must reach the table and press it. The energy bound is
// the body's own: the only source is the tracking spring, which stores at most
// 1/2 k (6 mm)^2 = 3.6 mJ; the total energy may not leave its start by three times that (a
// solver that invents energy leaves it; a frozen one fails the press instead).
class SofthandStabilityGrid : public ::testing::TestWithParam<std::tuple<double, double, double>> {
};

TEST_P(SofthandStabilityGrid, PressIntoTableEndsFiniteAndBounded) {
    const auto [youngs, contact_k, dt] = GetParam();
    SolverSettings settings;
    settings.contact_stiffness_n_per_m = contact_k;
    settings.friction_stiffness_n_per_m = contact_k;
    HandBuildOptions options;
    options.tissue.youngs_modulus_pa = youngs;
    HandModel model = buildHand(fingertipConfig(1), settings, options);
    const double radius = 0.008;
    const int table = model.simulation.addCollider(
        {HalfSpace{}, Vec3(0.0, 0.0, -radius - 0.001), Mat3::Identity(), 0.8});
    const int bone = model.bones.front().body;
    const Vec3 start = model.simulation.bodyPosition(bone);
    // Press 6 mm within 40 ms, then hold: at least 6 steps at the longest time step.
    const double duration = std::max(0.06, 6.0 * dt);
    const double start_energy = model.simulation.totalEnergy();
    constexpr double kPress = 0.006;
    const RunSummary summary = run(model, bone, dt, duration, [&](double t) {
        return Vec3(start + Vec3(0.0, 0.0, -kPress * std::min(1.0, t / 0.04)));
    });
    const double spring_energy = 0.5 * options.tracking_linear_n_per_m * kPress * kPress;
    std::printf(
        "E %.0e Pa, contact %.0e N/m, dt %.3f s: bone down %.2f mm, table force %.3f N, "
        "energy at most %.2f mJ above its start, %d of %d steps rescaled, %d frozen\n",
        youngs, contact_k, dt, 1e3 * (start - model.simulation.bodyPosition(bone)).z(),
        -model.simulation.forceOnCollider(table).z(), 1e3 * (summary.max_energy_j - start_energy),
        summary.rescaled_steps, summary.steps, summary.frozen_steps);
    EXPECT_TRUE(summary.finite);
    EXPECT_LT(summary.max_energy_j - start_energy, 3.0 * spring_energy);
    EXPECT_LT(summary.max_distance_m, 0.1);
    EXPECT_EQ(summary.final_inverted, 0);
    EXPECT_EQ(summary.frozen_steps, 0);
    // The press happened: the pad reached the table (1 mm below it) and pushes on it.
    EXPECT_GT((start - model.simulation.bodyPosition(bone)).z(), 0.0009);
    EXPECT_LT(model.simulation.forceOnCollider(table).z(), 0.0);
}

INSTANTIATE_TEST_SUITE_P(TissueContactTimestep, SofthandStabilityGrid,
                         ::testing::Combine(::testing::Values(1e3, 1e5, 1e7),
                                            ::testing::Values(1e2, 1e4, 1e6),
                                            ::testing::Values(0.001, 0.033)));

TEST(SofthandStability, TenCentimetreTeleportIsAbsorbedAndReported) {
    SolverSettings settings;
    HandModel model = buildHand(fingertipConfig(1), settings);
    const int bone = model.bones.front().body;
    const Vec3 start = model.simulation.bodyPosition(bone);
    const Vec3 jump(0.1, 0.0, 0.0);
    const RunSummary summary =
        run(model, bone, 0.005, 0.6, [&](double) { return Vec3(start + jump); });
    EXPECT_TRUE(summary.finite);
    EXPECT_TRUE(summary.any_clamped) << "a 10 cm jump must hit the speed clamp";
    EXPECT_LT(summary.max_abs_energy_j, 1.0);
    EXPECT_EQ(summary.final_inverted, 0);
    EXPECT_LT((model.simulation.bodyPosition(bone) - (start + jump)).norm(), 0.01);
}

TEST(SofthandStability, InvertedElementsRecover) {
    SolverSettings settings;
    settings.gravity_m_per_s2 = Vec3::Zero();
    HandModel model = buildHand(fingertipConfig(2), settings);
    auto& sim = model.simulation;
    // Mirror every node of the pad's lower half through the bone axis plane z = 0: the
    // elements there turn inside out.
    for (int i = 0; i < sim.nodeCount(); ++i) {
        const Vec3 p = sim.nodePosition(i);
        if (p.z() < -0.004) {
            sim.setNodePosition(i, Vec3(p.x(), p.y(), -0.2 * p.z()));
        }
    }
    const int bone = model.bones.front().body;
    const Vec3 start = sim.bodyPosition(bone);
    const double initial_energy = sim.totalEnergy();
    StepReport first = sim.step(0.01);
    EXPECT_GT(first.inverted_elements, 0);
    const RunSummary summary = run(model, bone, 0.01, 1.0, [&](double) { return start; });
    EXPECT_TRUE(summary.finite);
    EXPECT_EQ(summary.final_inverted, 0);
    // The inversion stores energy; recovering releases it and must never add to it.
    EXPECT_LE(summary.max_abs_energy_j, initial_energy);
}

TEST(SofthandStability, SliverElementsStayFinite) {
    SolverSettings settings;
    settings.contact_stiffness_n_per_m = 1e4;
    Simulation sim(settings);
    // A layer of cells 1e-8 m thick: tetrahedra with aspect ratio ~1e6.
    const std::vector<double> xs{0.0, 0.004, 0.004 + 1e-8, 0.008};
    sim.addTissue(makeGridMesh(xs, xs, {0.0, 0.004, 0.008}), TissueMaterial{});
    sim.addCollider({HalfSpace{}, Vec3(0.0, 0.0, 0.0005), Mat3::Identity(), 0.5});
    double max_energy = 0.0;
    for (int s = 0; s < 100; ++s) {
        const StepReport report = sim.step(0.01);
        ASSERT_TRUE(std::isfinite(report.energy_j));
        max_energy = std::max(max_energy, std::abs(report.energy_j));
    }
    for (int i = 0; i < sim.nodeCount(); ++i) {
        ASSERT_TRUE(sim.nodePosition(i).allFinite());
        EXPECT_GT(sim.nodePosition(i).z(), -0.002);  // rests on the plane at z = 0.5 mm
    }
    EXPECT_LT(max_energy, 1.0);
}

TEST(SofthandStability, NanTrackingInputIsRejectedWithAReason) {
    SolverSettings settings;
    HandModel model = buildHand(fingertipConfig(1), settings);
    auto& sim = model.simulation;
    const int bone = model.bones.front().body;
    const Vec3 start = sim.bodyPosition(bone);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_FALSE(sim.setTrackingTarget(bone, Vec3(nan, 0.0, 0.0), Mat3::Identity()));
    const StepReport report = sim.step(0.01);
    EXPECT_TRUE(report.rejected_input);
    EXPECT_THAT(report.rejection_reason, ::testing::HasSubstr("not finite"));
    Mat3 bad_rotation = Mat3::Identity();
    bad_rotation(0, 0) = nan;
    EXPECT_FALSE(sim.setTrackingTarget(bone, start, bad_rotation));
    EXPECT_TRUE(sim.step(0.01).rejected_input);
    const StepReport bad_dt = sim.step(nan);
    EXPECT_TRUE(bad_dt.rejected_input);
    EXPECT_THAT(bad_dt.rejection_reason, ::testing::HasSubstr("time step"));
    for (int s = 0; s < 20; ++s) {
        EXPECT_FALSE(sim.step(0.01).rejected_input);
    }
    EXPECT_TRUE(sim.bodyPosition(bone).allFinite());
    EXPECT_LT((sim.bodyPosition(bone) - start).norm(), 0.005);
}

}  // namespace
}  // namespace haptic::softhand
