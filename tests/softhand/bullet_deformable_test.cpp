// The Bullet comparison's inputs: the fingertip it rebuilds is the hand builder's, node for
// node, and Bullet's soft body built from it keeps the nodes, tetrahedra, volume and mass;
// pressed into the table it pushes the table down.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "bullet_fingertip.hpp"
#include "fingertip_press_scene.hpp"

namespace haptic::softhand::bench {
namespace {

class BulletFingertipMesh : public ::testing::TestWithParam<int> {};

TEST_P(BulletFingertipMesh, MatchesTheHandBuilderNodeForNode) {
    const int level = GetParam();
    const FingertipModel model = fingertipModel(level);
    const HandModel built = buildHand(handConfig(config::HandModel::kFingertip, level), {});
    const Simulation& sim = built.simulation;
    ASSERT_EQ(static_cast<int>(model.mesh.nodes_m.size()), sim.nodeCount());
    ASSERT_EQ(static_cast<int>(model.mesh.tets.size()), sim.tetCount());
    double mass = 0.0;
    for (int i = 0; i < sim.nodeCount(); ++i) {
        EXPECT_LT((model.mesh.nodes_m[i] - sim.nodeRestPosition(i)).norm(), 1e-12) << i;
        mass += sim.nodeMass(i);
    }
    const BoneInfo& bone = built.bones.front();
    EXPECT_LT((model.bone_position_m - sim.bodyPosition(bone.body)).norm(), 1e-12);
    EXPECT_NEAR(model.bone_mass_kg, sim.body(bone.body).mass, 1e-12);
    EXPECT_NEAR(model.bone_inertia_kg_m2.y(), sim.body(bone.body).inertia_body(1, 1), 1e-15);
    EXPECT_GT(model.bone_nodes.size(), 3U);

    const BulletFingertip bullet(model, solverSettings(30, 1e-4), {});
    EXPECT_EQ(bullet.nodeCount(), sim.nodeCount());
    EXPECT_EQ(bullet.tetCount(), sim.tetCount());
    EXPECT_EQ(bullet.anchorCount(), static_cast<int>(model.bone_nodes.size()));
    EXPECT_NEAR(bullet.tissueMass(), mass, 1e-5 * mass);  // single-precision Bullet
    EXPECT_NEAR(bullet.tissueVolume() * model.material.density_kg_per_m3, mass, 1e-5 * mass);
    for (int i = 0; i < sim.nodeCount(); ++i) {
        EXPECT_LT((bullet.nodePosition(i) - sim.nodeRestPosition(i)).norm(), 1e-8) << i;
    }
}

INSTANTIATE_TEST_SUITE_P(Levels, BulletFingertipMesh, ::testing::Values(1, 2));

TEST(BulletFingertipPress, HangsStillAndPushesTheTableOnlyWhenPressed) {
    const FingertipModel model = fingertipModel(1);
    BulletSettings settings;
    settings.drive = BoneDrive::kKinematic;
    BulletFingertip bullet(model, solverSettings(30, 1e-4), settings);
    // Hanging 1 mm above the table: no force, and the pad keeps its shape (sag well under
    // 0.2 mm; rho g L^2 / E is about 0.02 mm).
    for (int s = 0; s < 20; ++s) {
        bullet.setBoneTarget(model.bone_position_m);
        bullet.step(kDt);
        EXPECT_EQ(bullet.tableForceZ(), 0.0) << s;
    }
    for (int i = 0; i < bullet.nodeCount(); ++i) {
        EXPECT_LT((bullet.nodePosition(i) - model.mesh.nodes_m[i]).norm(), 2e-4) << i;
    }
    // The bone moved 1.5 mm down (the pad 0.5 mm past touching): the table is pushed down.
    double force = 0.0;
    for (int s = 0; s < 40; ++s) {
        bullet.setBoneTarget(model.bone_position_m + Vec3(0.0, 0.0, -0.0015 * (s + 1) / 40.0));
        bullet.step(kDt);
        ASSERT_TRUE(bullet.finite()) << s;
        force = std::min(force, bullet.tableForceZ());
    }
    EXPECT_LT(force, 0.0);
}

}  // namespace
}  // namespace haptic::softhand::bench
