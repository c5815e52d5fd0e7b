// Each shipped scene builds only what it needs: the fingertip scene the distal phalanx of its
// finger, the one-finger scene that finger and the palm, the grasp scene the two fingers it
// names, the whole hand all five. Sizes are printed for the record.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "haptic/config/device.hpp"
#include "haptic/config/scene.hpp"
#include "haptic/softhand/scene_simulation.hpp"

namespace haptic::softhand {
namespace {

using ::testing::ElementsAre;
using ::testing::UnorderedElementsAreArray;

struct Built {
    SceneSize size;
    std::set<std::string> fingers;  // of every bone but the palm
};

Built build(const std::string& file) {
    const config::SceneConfig scene =
        config::loadSceneConfig(std::string(HAPTIC_SOURCE_DIR) + "/config/scenes/" + file);
    std::vector<DeviceRequest> devices;
    for (const auto& [name, binding] : scene.devices) {
        const bool kinesthetic = name == "exo";
        devices.push_back({name, binding.finger, kinesthetic, {{0.0, 0.0, -0.012}, {}}, 64});
    }
    const SceneSimulation sim(scene, devices, realtimeSceneSettings(scene.solver));
    Built out{sim.size(), {}};
    for (const BoneInfo& bone : sim.model().bones) {
        if (bone.finger) {
            out.fingers.insert(std::string(config::toString(*bone.finger)));
        }
    }
    std::printf("%s: %s\n", file.c_str(), toString(out.size).c_str());
    return out;
}

// The scene's solver keys (newton_iterations, pcg_max_iterations, helper_thread) reach the
// solver the scene builds, through the settings handsim builds it with.
TEST(SceneSolverLimits, TheScenesSolverKeysReachItsSolver) {
    config::SceneConfig scene =
        config::loadSceneConfig(std::string(HAPTIC_SOURCE_DIR) + "/config/scenes/default.yaml");
    const SolverSettings shipped = SceneSimulation(scene, {}, realtimeSceneSettings(scene.solver))
                                       .model()
                                       .simulation.settings();
    EXPECT_EQ(shipped.max_newton_iterations, 2);
    EXPECT_EQ(shipped.pcg_max_iterations, 30);
    scene.solver.newton_iterations = 3;
    scene.solver.pcg_max_iterations = 7;
    scene.solver.helper_thread = true;  // the default scene ships it off
    const SolverSettings changed = SceneSimulation(scene, {}, realtimeSceneSettings(scene.solver))
                                       .model()
                                       .simulation.settings();
    EXPECT_EQ(changed.max_newton_iterations, 3);
    EXPECT_EQ(changed.pcg_max_iterations, 7);
    EXPECT_FALSE(shipped.use_helper_thread);
    // Only where a second core can take it (withRealtimeLimits).
    EXPECT_EQ(changed.use_helper_thread, std::thread::hardware_concurrency() >= 2);
}

TEST(SceneSize, TheThimbleSceneBuildsTheDistalPhalanxOnly) {
    const Built built = build("thimble_only.yaml");
    EXPECT_THAT(built.size.bone_names, ElementsAre("index_distal"));
    EXPECT_EQ(built.size.joints, 0);
    EXPECT_EQ(built.size.nodes, 169);  // resolution 1, docs/benchmarks.md
    EXPECT_GT(built.size.colliders, 0);
}

TEST(SceneSize, TheDefaultSceneBuildsOneFingerAndThePalm) {
    const Built built = build("default.yaml");
    EXPECT_THAT(built.size.bone_names, UnorderedElementsAreArray({"palm", "index_proximal",
                                                                  "index_middle", "index_distal"}));
    EXPECT_THAT(built.fingers, ElementsAre("index"));
    EXPECT_EQ(built.size.joints, 3);
}

TEST(SceneSize, TheGraspSceneBuildsTheThumbAndTheIndexOnly) {
    const Built built = build("grasp_box.yaml");
    EXPECT_EQ(built.size.bone_names.size(), 7U);
    EXPECT_THAT(built.fingers, UnorderedElementsAreArray({"thumb", "index"}));
}

TEST(SceneSize, TheWholeHandSceneBuildsFiveFingers) {
    const Built built = build("whole_hand.yaml");
    EXPECT_EQ(built.size.bone_names.size(), 16U);
    EXPECT_EQ(built.fingers.size(), 5U);
    EXPECT_EQ(built.size.joints, 15);
}

// hapticd judges the thimble's force limits with the pad model the sim sends (its samples'
// weights) but never softer in total than the device file's safety.min_pad_stiffness_n_per_m.
// That floor is a guard against a sim gone wrong, so every shipped scene's pad must be well
// above it (twice), or the floor would be the model.
TEST(SceneSize, EveryShippedThimblePadIsStifferThanTheDevicesFloor) {
    const config::DeviceConfig thimble =
        config::loadDeviceConfig(std::string(HAPTIC_SOURCE_DIR) + "/config/devices/thimble.yaml");
    const double floor = thimble.safety.min_pad_stiffness_n_per_m;
    ASSERT_GT(floor, 0.0);
    int checked = 0;
    for (const char* file :
         {"default.yaml", "thimble_only.yaml", "grasp_box.yaml", "whole_hand.yaml"}) {
        const config::SceneConfig scene =
            config::loadSceneConfig(std::string(HAPTIC_SOURCE_DIR) + "/config/scenes/" + file);
        const auto binding = scene.devices.find("thimble");
        if (binding == scene.devices.end()) {
            continue;
        }
        const SceneSimulation sim(scene,
                                  {{"thimble", binding->second.finger, false,
                                    thimble.thimble().finger_calibration.T_finger_device,
                                    thimble.thimble().optimiser.pad_samples}},
                                  realtimeSceneSettings(scene.solver));
        msgs::ContactSurface surface;
        sim.fill(0, surface);
        double total = 0.0;
        for (const auto& sample : surface.samples) {
            total += sample.weight;
        }
        std::printf("%s: the thimble's pad model %.0f N/m in total (floor %.0f N/m)\n", file, total,
                    floor);
        EXPECT_GT(total, 2.0 * floor) << file;
        ++checked;
    }
    EXPECT_GE(checked, 2);
}

}  // namespace
}  // namespace haptic::softhand
