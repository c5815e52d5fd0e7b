// The grasp scene (config/scenes/grasp_box.yaml) end to end: the soft thumb and index, driven
// by the scripted grasp_lift_place_push motion through elastic tracking, pinch a box that
// lives in Bullet (btDiscreteDynamicsWorld through BulletCoupling), lift it, set it back on
// the table and push it into a second box. Everything the box does comes from Bullet: the
// hand only holds the box's duplicate, tied to Bullet's body by the 6-DoF spring.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "haptic/config/scene.hpp"
#include "haptic/softhand/scene_simulation.hpp"

namespace haptic::softhand {
namespace {

constexpr int kTable = 0;  // objects in grasp_box.yaml: table, box, obstacle
constexpr int kBox = 1;
constexpr int kObstacle = 2;

double halfExtent(const config::SceneObject& object, int axis) {
    return std::get<config::BoxShape>(object.shape).half_extents_m[static_cast<std::size_t>(axis)];
}

double tiltRad(const Mat3& rotation) {
    return std::acos(std::clamp(rotation(2, 2), -1.0, 1.0));
}

// Height of a box's lowest corner.
double lowestCorner(const Vec3& centre, const Mat3& rotation, const config::SceneObject& box) {
    double lowest = centre.z();
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3 local((corner & 1 ? 1 : -1) * halfExtent(box, 0),
                         (corner & 2 ? 1 : -1) * halfExtent(box, 1),
                         (corner & 4 ? 1 : -1) * halfExtent(box, 2));
        lowest = std::min(lowest, (centre + rotation * local).z());
    }
    return lowest;
}

// How the scene is solved: handsim's real-time limits, the accurate solver with PCG capped
// at 40, and a box 2.5 times heavier (the grip must carry it, not the friction margin of the
// shipped one).
struct GraspCase {
    const char* name;
    bool realtime_limits;
    double box_mass_kg;  // 0: the scene's
};

class SofthandGrasp : public ::testing::TestWithParam<GraspCase> {};

// At 60 Hz the pinch did not hold (the box squirted out of it at the end of the lift with
// every PCG cap tried); the scene now runs at 200 Hz, level 0 (config/scenes/grasp_box.yaml).
TEST_P(SofthandGrasp, PinchLiftPlaceAndPushABoxInBullet) {
    config::SceneConfig scene =
        config::loadSceneConfig(std::string(HAPTIC_SOURCE_DIR) + "/config/scenes/grasp_box.yaml");
    ASSERT_EQ(scene.tracking.script, config::TrackingScript::kGraspLiftPlacePush);
    if (GetParam().box_mass_kg > 0.0) {
        scene.objects[kBox].mass_kg = GetParam().box_mass_kg;
    }
    const config::SceneObject& box = scene.objects[kBox];
    const config::SceneObject& obstacle = scene.objects[kObstacle];
    ASSERT_EQ(box.name, scene.tracking.target_object);

    SceneSimulationSettings settings;
    if (GetParam().realtime_limits) {
        settings = realtimeSceneSettings(scene.solver);
    } else {
        settings.solver.pcg_max_iterations = 40;
    }
    SceneSimulation sim(scene, {}, settings);
    ASSERT_EQ(sim.model().bones.size(), 7U) << "palm, thumb and index only";
    const GraspLiftPlacePushScript script(sim.trackedHand(), scene.hand, box, false);
    sim.reset(script.at(0.0));
    const BulletCoupling& engine = sim.coupling();
    const Vec3 box_start = engine.enginePosition(kBox);
    const Vec3 obstacle_start = engine.enginePosition(kObstacle);
    const double box_half_z = halfExtent(box, 2);
    const double contact_gap = halfExtent(box, 0) + halfExtent(obstacle, 0);

    using S = GraspLiftPlacePushScript;
    const double dt = 1.0 / scene.rate_hz;
    const int steps = static_cast<int>(std::ceil(S::kOpenEnd / dt));
    double lowest_while_up = 1e9;      // box z between the end of the lift and the set-down
    double largest_box_force_n = 0.0;  // box-obstacle contact force in Bullet
    double smallest_gap_m = 1e9;       // obstacle x - box x
    // The box just before the push starts, once it has been set down.
    double placed_z = 0.0;
    double placed_corner_z = 0.0;
    double placed_tilt = 0.0;
    double placed_table_force_n = 0.0;
    Vec3 placed_drift = Vec3::Zero();
    int rejected = 0;
    for (int s = 1; s <= steps; ++s) {
        const double t = s * dt;
        ASSERT_FALSE(sim.setHandPose(script.at(t)).has_value());
        const StepReport report = sim.step(dt);
        ASSERT_TRUE(std::isfinite(report.energy_j)) << "t = " << t;
        rejected += report.rejected_input ? 1 : 0;
        const Vec3 box_now = engine.enginePosition(kBox);
        const Vec3 obstacle_now = engine.enginePosition(kObstacle);
        ASSERT_TRUE(box_now.allFinite() && obstacle_now.allFinite()) << "t = " << t;
        if (t >= S::kLiftEnd && t <= S::kPlaceStart) {
            lowest_while_up = std::min(lowest_while_up, box_now.z());
        }
        if (t <= S::kPushStart) {
            placed_z = box_now.z();
            placed_corner_z = lowestCorner(box_now, engine.engineRotation(kBox), box);
            placed_tilt = tiltRad(engine.engineRotation(kBox));
            placed_table_force_n = engine.engineContactForce(kBox, kTable);
            placed_drift = box_now - box_start;
        }
        largest_box_force_n =
            std::max(largest_box_force_n, engine.engineContactForce(kBox, kObstacle));
        smallest_gap_m = std::min(smallest_gap_m, obstacle_now.x() - box_now.x());
    }
    EXPECT_EQ(rejected, 0);
    std::printf(
        "lifted %.1f mm; placed z %.1f mm, corner %.1f mm, tilt %.3f rad, table force %.3f N; "
        "box-box force max %.3f N, obstacle moved %.1f mm, smallest centre gap %.1f mm\n",
        1e3 * (lowest_while_up - box_start.z()), 1e3 * placed_z, 1e3 * placed_corner_z, placed_tilt,
        placed_table_force_n, largest_box_force_n,
        1e3 * (engine.enginePosition(kObstacle).x() - obstacle_start.x()), 1e3 * smallest_gap_m);

    // Lifted: the box rose with the hand by most of the 5 cm and stayed in the pinch (46.0-46.7
    // mm in all three cases on 2026-11-27; docs/softhand.md).
    EXPECT_GT(lowest_while_up - box_start.z(), 0.044)
        << "the box did not rise with the hand (or slipped out of the pinch)";

    // Set down: back on Bullet's table, at its half height, upright, near where it stood.
    // (Still in the pinch, it may lean a little on one bottom edge.)
    EXPECT_NEAR(placed_z, box_half_z, 3e-3) << "the box rests on the table";
    EXPECT_NEAR(placed_corner_z, 0.0, 1.5e-3) << "its lowest corner touches the table";
    EXPECT_GT(placed_table_force_n, 0.0) << "Bullet's table carries it";
    EXPECT_LT(placed_tilt, 0.025) << "rad";
    EXPECT_LT(std::hypot(placed_drift.x(), placed_drift.y()), 0.015);

    // Pushed against the obstacle: the boxes touched in Bullet, the obstacle slid along +x,
    // neither passed through the other and both stayed on the table.
    const Vec3 box_end = engine.enginePosition(kBox);
    const Vec3 obstacle_end = engine.enginePosition(kObstacle);
    EXPECT_GT(largest_box_force_n, 0.05) << "no box-box contact force in Bullet";
    EXPECT_GT(obstacle_end.x() - obstacle_start.x(), 0.01) << "the obstacle did not move";
    EXPECT_GT(smallest_gap_m, contact_gap - 2e-3) << "the boxes interpenetrated";
    EXPECT_NEAR(lowestCorner(box_end, engine.engineRotation(kBox), box), 0.0, 1.5e-3);
    EXPECT_NEAR(lowestCorner(obstacle_end, engine.engineRotation(kObstacle), obstacle), 0.0,
                1.5e-3);
    EXPECT_LT(tiltRad(engine.engineRotation(kObstacle)), 0.1) << "rad";
    EXPECT_GT(box_end.x() - box_start.x(), 0.02) << "the hand pushed the box along +x";
}

INSTANTIATE_TEST_SUITE_P(SolverSettingsAndBoxMass, SofthandGrasp,
                         ::testing::Values(GraspCase{"HandsimLimits", true, 0.0},
                                           GraspCase{"AccurateCap40", false, 0.0},
                                           GraspCase{"HandsimLimitsBoxOf30g", true, 0.03}),
                         [](const ::testing::TestParamInfo<GraspCase>& info) {
                             return std::string(info.param.name);
                         });

}  // namespace
}  // namespace haptic::softhand
