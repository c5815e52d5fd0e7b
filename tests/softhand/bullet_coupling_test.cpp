// Bullet as the external engine, coupled through object duplicates (docs/algorithms.md §2.5).

#include "haptic/softhand/bullet_coupling.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "haptic/softhand/elastic_tracking.hpp"
#include "haptic/softhand/hand_builder.hpp"

namespace haptic::softhand {
namespace {

config::SceneObject table(double height) {
    config::SceneObject object;
    object.name = "table";
    object.shape = config::PlaneShape{};
    object.pose.position_m = {0.0, 0.0, height};
    object.friction = 0.4;
    return object;
}

config::SceneObject box(const Vec3& center, double half, double mass) {
    config::SceneObject object;
    object.name = "box";
    object.shape = config::BoxShape{{half, half, half}};
    object.pose.position_m = {center.x(), center.y(), center.z()};
    object.mass_kg = mass;
    object.friction = 0.4;
    return object;
}

config::HandConfig fingertip() {
    config::HandConfig hand;
    hand.model = config::HandModel::kFingertip;
    hand.finger = config::Finger::kIndex;
    hand.resolution = 1;
    hand.anthropometry = {0.19, 0.085, 0.016};
    return hand;
}

// The scene's shape keys and its pose's rpy_deg reach the colliders the soft hand touches: a
// box turned 90 degrees about z lies along y, a sphere has its radius.
TEST(SofthandBulletCoupling, TheObjectsRotationAndSizesReachTheirColliders) {
    config::SceneObject bar;
    bar.name = "bar";
    bar.shape = config::BoxShape{{0.04, 0.01, 0.01}};
    bar.pose.rpy_rad = {0.0, 0.0, std::numbers::pi / 2.0};
    config::SceneObject ball;
    ball.name = "ball";
    ball.shape = config::SphereShape{0.02};
    ball.pose.position_m = {0.2, 0.0, 0.0};
    config::SceneObject rod;
    rod.name = "rod";
    rod.shape = config::CapsuleShape{0.005, 0.03};
    rod.pose.position_m = {-0.2, 0.0, 0.0};
    Simulation sim;
    const BulletCoupling coupling({bar, ball, rod}, sim);
    const auto depth = [&](int object, const Vec3& p) {
        return sim.queryCollider(coupling.colliderOf(object), p).phi_m;
    };
    // The bar's long axis is now y: 35 mm along y is inside, along x outside by 25 mm.
    EXPECT_NEAR(depth(0, Vec3(0.0, 0.035, 0.0)), -0.005, 1e-9);
    EXPECT_NEAR(depth(0, Vec3(0.035, 0.0, 0.0)), 0.025, 1e-9);
    EXPECT_NEAR(depth(1, Vec3(0.2 + 0.025, 0.0, 0.0)), 0.005, 1e-9);
    EXPECT_NEAR(depth(1, Vec3(0.2, 0.015, 0.0)), -0.005, 1e-9);
    // The capsule's axis is z: its radius around it, its half height plus the radius along it.
    EXPECT_NEAR(depth(2, Vec3(-0.2 + 0.007, 0.0, 0.02)), 0.002, 1e-9);
    EXPECT_NEAR(depth(2, Vec3(-0.2, 0.0, 0.036)), 0.001, 1e-9);
}

TEST(SofthandBulletCoupling, BoxSettlesOnTheTableInBulletAndTheDuplicateFollows) {
    Simulation sim;
    BulletCoupling coupling({table(0.0), box(Vec3(0.3, 0.0, 0.03), 0.02, 0.1)}, sim);
    ASSERT_EQ(coupling.duplicateOf(0), -1);  // the table is static
    ASSERT_GE(coupling.duplicateOf(1), 0);
    for (int s = 0; s < 50; ++s) {
        sim.step(0.01);
        coupling.exchange(sim, 0.01);
    }
    EXPECT_NEAR(coupling.enginePosition(1).z(), 0.02, 1e-3);  // fell 1 cm and rests
    EXPECT_LT((sim.bodyPosition(coupling.duplicateOf(1)) - coupling.enginePosition(1)).norm(),
              2e-3);
}

TEST(SofthandBulletCoupling, FingertipPushesABoxAcrossTheTable) {
    SolverSettings settings;
    settings.contact_stiffness_n_per_m = 3000.0;
    HandModel model = buildHand(fingertip(), settings);
    // Box face 1 mm ahead of the pad's tip (x = L + r), the table 2 cm below the bone axis.
    const double tip_x = model.bones[0].length_m + 0.008;
    const double half = 0.02;
    BulletCoupling coupling({table(-half), box(Vec3(tip_x + 0.001 + half, 0.0, 0.0), half, 0.05)},
                            model.simulation);
    ElasticTracking tracking(model);
    const BonePose start{model.simulation.bodyPosition(model.bones[0].body), Mat3::Identity()};
    const double start_box_x = coupling.enginePosition(1).x();
    const double dt = 0.01;
    double largest_push_n = 0.0;
    for (int s = 0; s < 80; ++s) {
        const double t = (s + 1) * dt;
        BonePose target = start;
        target.position_m.x() += 0.03 * std::min(1.0, t / 0.6);
        ASSERT_TRUE(tracking.setTrackedPoses(std::span(&target, 1), nullptr));
        tracking.update(model, dt);
        ASSERT_TRUE(std::isfinite(model.simulation.step(dt).energy_j));
        coupling.exchange(model.simulation, dt);
        largest_push_n =
            std::max(largest_push_n, model.simulation.forceOnCollider(coupling.colliderOf(1)).x());
    }
    const Vec3 box_now = coupling.enginePosition(1);
    EXPECT_GT(box_now.x() - start_box_x, 0.01) << "the push reached Bullet";
    EXPECT_NEAR(box_now.z(), 0.0, 2e-3) << "the box still rests on Bullet's table";
    EXPECT_GT(largest_push_n, 0.0) << "the pad pushed the duplicate along +x";
}

}  // namespace
}  // namespace haptic::softhand
