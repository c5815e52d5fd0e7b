// The daemon-wide keys of daemon.yaml whose effect only the running daemon shows, each changed
// from the shipped value and its effect read off what hapticd publishes. (The per-device
// safety keys are covered where they act: runtime_test's DeviceRuntime key tests.)

#include "device_safety_rig.hpp"

namespace haptic::testing {
namespace {

class TelemetryDecimationTest : public DeviceSafetyTest {
  protected:
    TelemetryDecimationTest() {
        replaceLine(config_.dir / "daemon.yaml", "telemetry_decimation: 1 ",
                    "telemetry_decimation: 10 ");
    }
};

TEST_F(TelemetryDecimationTest, TelemetryCarriesEveryTenthTickOfBothDevices) {
    const auto samples = collectTelemetry(kAllDevices, 1s);
    std::map<std::size_t, std::vector<std::uint64_t>> ticks;
    for (const auto& sample : samples) {
        ticks[sample.device_index].push_back(sample.tick);
    }
    ASSERT_EQ(ticks.size(), 2U);
    for (const auto& [device, device_ticks] : ticks) {
        ASSERT_GT(device_ticks.size(), 10U) << "device " << device;
        for (const std::uint64_t tick : device_ticks) {
            ASSERT_EQ(tick % 10, 0U) << "device " << device;
        }
        // Best effort, as at every tick: a stalled non-RT side may lose a few, not a tenth.
        const std::uint64_t span = (device_ticks.back() - device_ticks.front()) / 10 + 1;
        EXPECT_GT(device_ticks.size(), span * 9 / 10) << "device " << device;
        EXPECT_LE(device_ticks.size(), span) << "device " << device;
    }
}

}  // namespace
}  // namespace haptic::testing
