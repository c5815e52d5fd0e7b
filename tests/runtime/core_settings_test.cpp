// Each loop key of daemon.yaml reaches the DaemonCore hapticd builds (runtime::coreSettings):
// the core's behaviour under each setting is tested on CoreSettings directly
// (tests/daemon/daemon_core_test.cpp: DaemonCoreRearm, DaemonCoreOverruns, DaemonCoreRate,
// the sim timeout's fade), so this closes the chain from the file. Values unlike the shipped
// ones and unlike CoreSettings' defaults, so a key dropped on the way fails here.

#include "haptic/runtime/core_settings.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "haptic/config/daemon.hpp"

namespace haptic::testing {
namespace {

namespace fs = std::filesystem;

// The shipped configuration directory, copied, with daemon.yaml's `key: value` lines of the
// loop section replaced.
class EditedConfig {
  public:
    EditedConfig()
        : dir_(fs::temp_directory_path() / ("core_settings_" + std::to_string(::getpid()))) {
        fs::remove_all(dir_);
        fs::copy(HAPTIC_CONFIG_DIR, dir_, fs::copy_options::recursive);
    }
    ~EditedConfig() { fs::remove_all(dir_); }
    EditedConfig(const EditedConfig&) = delete;
    EditedConfig& operator=(const EditedConfig&) = delete;

    void set(const std::string& key, const std::string& value) {
        std::ifstream in(daemonFile());
        std::stringstream out;
        std::string line;
        bool replaced = false;
        while (std::getline(in, line)) {
            const std::string prefix = "  " + key + ":";
            if (!replaced && line.rfind(prefix, 0) == 0) {
                line = prefix + " " + value;
                replaced = true;
            }
            out << line << '\n';
        }
        ASSERT_TRUE(replaced) << key << " not in the shipped daemon.yaml";
        std::ofstream(daemonFile()) << out.str();
    }
    [[nodiscard]] fs::path daemonFile() const { return dir_ / "daemon.yaml"; }

  private:
    fs::path dir_;
};

TEST(CoreSettings, EveryLoopKeyOfTheFileReachesTheCore) {
    EditedConfig edited;
    edited.set("rate_hz", "2000");  // faster: 500 Hz fails the passivity check
    edited.set("sim_timeout_ms", "35");
    edited.set("sim_rearm_after_ms", "300");
    edited.set("status_rate_hz", "50");
    edited.set("telemetry_decimation", "4");
    edited.set("overrun_limit", "7");
    edited.set("overrun_window_ms", "250");
    const config::DaemonConfig cfg = config::loadDaemonConfig(edited.daemonFile());
    const daemon::CoreSettings settings = runtime::coreSettings(cfg, "test-version");
    EXPECT_EQ(settings.rate_hz, 2000);
    EXPECT_EQ(settings.sim_timeout_ns, 35'000'000);
    EXPECT_EQ(settings.sim_rearm_after_ns, 300'000'000);
    EXPECT_EQ(settings.status_period_ns, 20'000'000);
    EXPECT_EQ(settings.telemetry_decimation, 4U);
    EXPECT_EQ(settings.overrun_limit, 7U);
    EXPECT_EQ(settings.overrun_window_ns, 250'000'000);
    EXPECT_EQ(settings.version, "test-version");
    EXPECT_EQ(settings.config_digest, config::configurationDigest(cfg));
}

// The stall that is hapticd's own fault (110) is the shortest command timeout of its devices:
// a loop stopped that long has let a device time out.
TEST(CoreSettings, TheStallLimitIsTheShortestCommandTimeout) {
    EditedConfig edited;
    config::DaemonConfig cfg = config::loadDaemonConfig(edited.daemonFile());
    ASSERT_EQ(cfg.devices.size(), 2U);
    cfg.devices[0].can.command_timeout_ms = 40;
    cfg.devices[1].can.command_timeout_ms = 25;
    EXPECT_EQ(runtime::coreSettings(cfg, "").stall_limit_ns, 25'000'000);
    cfg.devices[0].can.command_timeout_ms = 15;
    EXPECT_EQ(runtime::coreSettings(cfg, "").stall_limit_ns, 15'000'000);
    const auto devices = runtime::deviceDescriptors(cfg);
    ASSERT_EQ(devices.size(), 2U);
    EXPECT_EQ(devices[0].name, cfg.devices[0].name);
    EXPECT_EQ(devices[1].name, cfg.devices[1].name);
}

}  // namespace
}  // namespace haptic::testing
