// The scene's device bindings (devices.<name>.finger) as handsim reads them (deviceRequests,
// the executable's own code): each device of sim.yaml is computed on the finger the scene binds
// it to, and a binding the scene's hand cannot serve is refused by name.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "haptic/config/sim.hpp"
#include "haptic/softhand/scene_simulation.hpp"
#include "sim_app.hpp"

namespace haptic::handsim {
namespace {

using ::testing::HasSubstr;

const std::string kConfigDir = HAPTIC_CONFIG_DIR;

const softhand::DeviceRequest& requestNamed(const std::vector<softhand::DeviceRequest>& requests,
                                            const std::string& name) {
    for (const auto& request : requests) {
        if (request.name == name) {
            return request;
        }
    }
    throw std::out_of_range("no request for " + name);
}

TEST(HandsimDeviceBinding, EachDeviceIsComputedOnTheFingerTheSceneBindsItTo) {
    config::SimConfig cfg = config::loadSimConfig(kConfigDir + "/sim.yaml");
    ASSERT_EQ(cfg.devices.size(), 2U);
    const auto shipped = deviceRequests(cfg);
    EXPECT_EQ(requestNamed(shipped, "exo").finger, config::Finger::kIndex);
    EXPECT_TRUE(requestNamed(shipped, "exo").kinesthetic);
    EXPECT_EQ(requestNamed(shipped, "thimble").finger, config::Finger::kIndex);
    EXPECT_FALSE(requestNamed(shipped, "thimble").kinesthetic);
    for (const auto& device : cfg.devices) {
        if (device.isThimble()) {
            EXPECT_EQ(requestNamed(shipped, device.name).max_samples,
                      device.thimble().optimiser.pad_samples);
        }
    }

    // Bound to the middle finger: requested there, and the default scene (one index finger)
    // cannot serve it, which the soft hand says by name.
    cfg.scene.devices.at("thimble").finger = config::Finger::kMiddle;
    const auto rebound = deviceRequests(cfg);
    EXPECT_EQ(requestNamed(rebound, "thimble").finger, config::Finger::kMiddle);
    try {
        const softhand::SceneSimulation sim(cfg.scene, rebound);
        ADD_FAILURE() << "a thimble on a finger the scene does not build was accepted";
    } catch (const std::exception& e) {
        EXPECT_THAT(e.what(), HasSubstr("middle finger"));
    }

    // A device the scene does not bind at all is refused, naming it and the scene file.
    cfg.scene.devices.erase("thimble");
    try {
        (void)deviceRequests(cfg);
        ADD_FAILURE() << "an unbound device was accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_THAT(e.what(), HasSubstr("device 'thimble' is not bound to a finger in "));
    }
}

}  // namespace
}  // namespace haptic::handsim
