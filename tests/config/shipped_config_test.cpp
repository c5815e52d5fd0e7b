// The files in config/ load and say what their comments say. These values are what the demo
// and the end-to-end tests run with, so a change here should be a deliberate one.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <regex>
#include <string>

#include "haptic/config/config.hpp"
#include "test_support.hpp"

namespace haptic::config {
namespace {

namespace fs = std::filesystem;
using test::kConfigDir;
using test::kDataDir;
using test::resolved;

constexpr double kTol = 1e-12;

TEST(ShippedConfig, EveryDeviceAndSceneFileLoads) {
    int devices = 0;
    for (const auto& entry : fs::directory_iterator(kConfigDir / "devices")) {
        if (entry.path().extension() == ".yaml") {
            EXPECT_NO_THROW((void)loadDeviceConfig(entry.path())) << entry.path();
            ++devices;
        }
    }
    int scenes = 0;
    for (const auto& entry : fs::directory_iterator(kConfigDir / "scenes")) {
        if (entry.path().extension() == ".yaml") {
            EXPECT_NO_THROW((void)loadSceneConfig(entry.path())) << entry.path();
            ++scenes;
        }
    }
    EXPECT_GE(devices, 2);
    EXPECT_GE(scenes, 2);
}

// hapticd fades a device's force from 3/4 of sim_timeout_ms on, so a scene that delivers less
// often than that makes the force ripple at the sim rate (what the demo's 60 Hz scene did).
// 1.5 sim periods within the timeout leave the fade start half a period for step jitter.
TEST(ShippedConfig, EveryShippedSceneOutrunsTheDaemonsFade) {
    const DaemonConfig daemon = loadDaemonConfig(kConfigDir / "daemon.yaml");
    int scenes = 0;
    for (const auto& entry : fs::directory_iterator(kConfigDir / "scenes")) {
        if (entry.path().extension() != ".yaml") {
            continue;
        }
        const SceneConfig scene = loadSceneConfig(entry.path());
        const double period_ms = 1000.0 / scene.rate_hz;
        EXPECT_LE(1.5 * period_ms, daemon.loop.sim_timeout_ms)
            << entry.path() << ": " << scene.rate_hz << " Hz against sim_timeout_ms "
            << daemon.loop.sim_timeout_ms;
        ++scenes;
    }
    EXPECT_GE(scenes, 4);
}

TEST(ShippedConfig, Daemon) {
    const DaemonConfig cfg = loadDaemonConfig(kConfigDir / "daemon.yaml");
    EXPECT_EQ(cfg.log_level, LogLevel::kInfo);
    EXPECT_EQ(cfg.loop.rate_hz, 1000);
    EXPECT_EQ(cfg.loop.realtime, RealtimeMode::kEnforce);
    EXPECT_EQ(cfg.loop.priority, 80);
    EXPECT_EQ(cfg.loop.cpu_affinity, -1);
    EXPECT_EQ(cfg.loop.cpu_latency_us, 0);
    EXPECT_EQ(cfg.loop.sim_timeout_ms, 20);
    EXPECT_EQ(cfg.loop.sim_rearm_after_ms, 1000);
    EXPECT_EQ(cfg.loop.status_rate_hz, 20);
    EXPECT_EQ(cfg.loop.telemetry_decimation, 1);
    EXPECT_EQ(cfg.loop.overrun_limit, 100);
    EXPECT_EQ(cfg.loop.overrun_window_ms, 1000);
    // Off as shipped: the relay's id is the lab's (docs/hapticd.md, "Hardware E-stop").
    EXPECT_FALSE(cfg.estop_relay.enabled);
    EXPECT_EQ(cfg.estop_relay.bus_device, "exo");
    EXPECT_EQ(cfg.estop_relay.status_id, 0x0E0U);
    EXPECT_EQ(cfg.estop_relay.timeout_ms, 30);
    ASSERT_EQ(cfg.devices.size(), 2U);
    EXPECT_EQ(cfg.devices[0].name, "exo");
    EXPECT_EQ(cfg.devices[0].type(), DeviceType::kExoskeleton);
    EXPECT_EQ(cfg.devices[0].source, resolved(kConfigDir / "devices/exoskeleton.yaml"));
    EXPECT_EQ(cfg.devices[1].name, "thimble");
    EXPECT_EQ(cfg.devices[1].type(), DeviceType::kThimble);
    EXPECT_EQ(cfg.sim_link.transport, SimTransport::kIceoryx);
    EXPECT_EQ(cfg.dds.domain_id, 0);
    EXPECT_EQ(cfg.dds.profiles_file, resolved(kConfigDir / "dds_profiles.xml"));
    EXPECT_EQ(cfg.dds.participant_profile, "haptic_participant");
    ASSERT_TRUE(cfg.iceoryx.has_value());
    EXPECT_EQ(cfg.iceoryx->roudi_config, resolved(kConfigDir / "roudi.toml"));
}

TEST(ShippedConfig, Sim) {
    const SimConfig cfg = loadSimConfig(kConfigDir / "sim.yaml");
    EXPECT_EQ(cfg.cpu_latency_us, 0);
    EXPECT_EQ(cfg.scene.name, "default");
    EXPECT_EQ(cfg.scene.source, resolved(kConfigDir / "scenes/default.yaml"));
    EXPECT_EQ(cfg.sim_link.transport, SimTransport::kIceoryx);
    EXPECT_EQ(cfg.dds.participant_profile, "haptic_participant");
    ASSERT_EQ(cfg.devices.size(), 2U);
    for (const DeviceConfig& device : cfg.devices) {
        EXPECT_TRUE(cfg.scene.devices.contains(device.name)) << device.name;
    }
    // Every channel, as shipped (config/sim.yaml says why).
    ASSERT_TRUE(cfg.tracking_filter.has_value());
    ASSERT_TRUE(cfg.tracking_filter->angle_beta_s_per_rad.has_value());
    EXPECT_EQ(*cfg.tracking_filter->angle_beta_s_per_rad, 10.0);
    EXPECT_EQ(cfg.tracking_filter->min_cutoff_hz, 2.0);
    EXPECT_EQ(cfg.tracking_filter->position_beta_s_per_m, 50.0);
}

TEST(ShippedConfig, Exoskeleton) {
    const DeviceConfig cfg = loadDeviceConfig(kConfigDir / "devices/exoskeleton.yaml");
    EXPECT_EQ(cfg.name, "exo");
    ASSERT_TRUE(cfg.isExoskeleton());
    EXPECT_EQ(cfg.can.interface, "") << "a UDP bus: no SocketCAN interface";
    EXPECT_EQ(cfg.can.command_id, 0x101U);
    EXPECT_EQ(cfg.can.state_id, 0x181U);
    EXPECT_EQ(cfg.can.heartbeat_id, 0x701U);
    EXPECT_EQ(cfg.can.fault_id, 0x081U);
    EXPECT_EQ(cfg.can.heartbeat_timeout_ms, 50);
    EXPECT_EQ(cfg.can.state_timeout_ms, 10);
    EXPECT_EQ(cfg.can.command_timeout_ms, 10);
    EXPECT_EQ(cfg.can.transport, CanTransport::kUdp);
    EXPECT_EQ(cfg.can.udp_port, 47000);
    EXPECT_EQ(cfg.can.udp_slots, 4);
    EXPECT_DOUBLE_EQ(cfg.safety.max_force_n, 10.0);
    EXPECT_DOUBLE_EQ(cfg.safety.max_stiffness_n_per_m, 15000.0);
    EXPECT_DOUBLE_EQ(cfg.safety.max_velocity_m_per_s, 0.05);
    EXPECT_EQ(cfg.safety.fade_out_ms, 100);

    const ExoskeletonConfig& exo = cfg.exoskeleton();
    EXPECT_DOUBLE_EQ(exo.actuator.stroke_max_m, 0.025);
    EXPECT_DOUBLE_EQ(exo.actuator.max_force_n, 40.0);
    EXPECT_EQ(exo.finger.phalanx_lengths_m, (Vec3{0.043, 0.025, 0.019}));
    // Degrees in the file, radians in the struct.
    EXPECT_NEAR(exo.finger.joint_limits_rad[0].min, -20.0 * std::numbers::pi / 180.0, kTol);
    EXPECT_NEAR(exo.finger.joint_limits_rad[1].max, 110.0 * std::numbers::pi / 180.0, kTol);
    EXPECT_EQ(exo.linkage.actuator_base_m, (Vec2{-0.060, -0.014}));
    EXPECT_DOUBLE_EQ(exo.linkage.rod_length_m, 0.058);
    EXPECT_EQ(exo.rendering.method, RenderingMethod::kLinearizedSubspace);
    EXPECT_EQ(exo.rendering.max_constraints, 8);
    EXPECT_DOUBLE_EQ(exo.rendering.tracking_stiffness_nm_per_rad, 2.0);
    EXPECT_DOUBLE_EQ(exo.rendering.user_stiffness_nm_per_rad, 0.6);
    EXPECT_DOUBLE_EQ(exo.rendering.actuator_damping_n_s_per_m, 0.5);
    EXPECT_DOUBLE_EQ(exo.actuator.damping_n_s_per_m, 10.0);
    EXPECT_DOUBLE_EQ(exo.actuator.force_tolerance_n, 1.0);
    EXPECT_DOUBLE_EQ(exo.rendering.passivity_port_mass_kg, 0.1);
    // Off while the shipped method does not use rho (config/devices/exoskeleton.yaml says why).
    EXPECT_FALSE(exo.rendering.user_stiffness_estimate.enabled);
    EXPECT_DOUBLE_EQ(exo.rendering.user_stiffness_estimate.probe_amplitude_m, 25e-6);
    EXPECT_DOUBLE_EQ(exo.rendering.user_stiffness_estimate.probe_frequency_hz, 5.0);
    EXPECT_DOUBLE_EQ(exo.rendering.user_stiffness_estimate.probe_time_s, 1.5);
    EXPECT_THROW((void)cfg.thimble(), std::bad_variant_access);
}

TEST(ShippedConfig, ExoskeletonLinkageStaysWithinStroke) {
    // The assumed closure model documented in device.hpp must map the joint-limit box into
    // the actuator stroke, or the shipped numbers contradict each other.
    const ExoskeletonConfig exo =
        loadDeviceConfig(kConfigDir / "devices/exoskeleton.yaml").exoskeleton();
    const auto& l = exo.linkage;
    const auto& lim = exo.finger.joint_limits_rad;
    for (const double q1 : {lim[0].min, lim[0].max}) {
        for (const double q2 : {lim[1].min, lim[1].max}) {
            for (const double q3 : {lim[2].min, lim[2].max}) {
                const double x = std::cos(q1) * l.proximal_attachment_m[0] -
                                 std::sin(q1) * l.proximal_attachment_m[1] - l.actuator_base_m[0];
                const double y = std::sin(q1) * l.proximal_attachment_m[0] +
                                 std::cos(q1) * l.proximal_attachment_m[1] - l.actuator_base_m[1];
                const double stroke = std::hypot(x, y) - l.rod_length_m +
                                      l.distal_coupling_m_per_rad[0] * q2 +
                                      l.distal_coupling_m_per_rad[1] * q3;
                EXPECT_GE(stroke, exo.actuator.stroke_min_m) << q1 << " " << q2 << " " << q3;
                EXPECT_LE(stroke, exo.actuator.stroke_max_m) << q1 << " " << q2 << " " << q3;
            }
        }
    }
}

TEST(ShippedConfig, Thimble) {
    const DeviceConfig cfg = loadDeviceConfig(kConfigDir / "devices/thimble.yaml");
    EXPECT_EQ(cfg.name, "thimble");
    ASSERT_TRUE(cfg.isThimble());
    EXPECT_EQ(cfg.can.command_id, 0x102U);
    EXPECT_DOUBLE_EQ(cfg.safety.max_force_n, 1.5);
    EXPECT_DOUBLE_EQ(cfg.safety.min_pad_stiffness_n_per_m, 1000.0);

    const ThimbleConfig& thimble = cfg.thimble();
    EXPECT_DOUBLE_EQ(thimble.geometry.base_radius_m, 0.012);
    EXPECT_DOUBLE_EQ(thimble.geometry.platform_radius_m, 0.008);
    EXPECT_DOUBLE_EQ(thimble.geometry.crank_length_m, 0.010);
    EXPECT_DOUBLE_EQ(thimble.geometry.link_length_m, 0.016);
    EXPECT_NEAR(thimble.geometry.leg_angles_rad[1], 210.0 * std::numbers::pi / 180.0, kTol);
    EXPECT_NEAR(thimble.servos.min_rad, -30.0 * std::numbers::pi / 180.0, kTol);
    EXPECT_NEAR(thimble.servos.max_rad, 90.0 * std::numbers::pi / 180.0, kTol);
    EXPECT_NEAR(thimble.servos.max_rate_rad_per_s, 400.0 * std::numbers::pi / 180.0, kTol);
    EXPECT_DOUBLE_EQ(thimble.plate_radius_m, 0.008);
    EXPECT_NEAR(thimble.max_tilt_rad, 30.0 * std::numbers::pi / 180.0, kTol);
    EXPECT_DOUBLE_EQ(thimble.finger_calibration.contact_height_m, 0.018);
    EXPECT_DOUBLE_EQ(thimble.finger_calibration.max_indentation_m, 0.004);
    EXPECT_EQ(thimble.finger_calibration.T_finger_device.translation_m, (Vec3{0.0, 0.0, -0.012}));
    EXPECT_EQ(thimble.finger_calibration.T_finger_device.rpy_rad, (Vec3{0.0, 0.0, 0.0}));
    EXPECT_EQ(thimble.optimiser.max_iterations, 20);
    EXPECT_EQ(thimble.optimiser.pad_samples, 64);
    // Fitted to the FEM fingertip (FemErrorAnalysis.TheShippedPadLawIsTheOneFittedToTheFem...).
    EXPECT_DOUBLE_EQ(thimble.optimiser.pad_stiffening_depth_m, 0.1);
}

TEST(ShippedConfig, DefaultScene) {
    const SceneConfig cfg = loadSceneConfig(kConfigDir / "scenes/default.yaml");
    EXPECT_EQ(cfg.name, "default");
    EXPECT_EQ(cfg.rate_hz, 100);
    EXPECT_EQ(cfg.hand.model, HandModel::kFinger);
    EXPECT_EQ(cfg.hand.finger, Finger::kIndex);
    EXPECT_EQ(cfg.hand.resolution, 1);
    EXPECT_DOUBLE_EQ(cfg.hand.anthropometry.hand_length_m, 0.19);
    // 100 Hz leaves room to re-linearise once; the 200 Hz scenes keep one iteration.
    EXPECT_EQ(cfg.solver, (SolverLimits{2, 30}));
    EXPECT_FALSE(cfg.solver.helper_thread) << "off unless a scene turns it on";

    ASSERT_EQ(cfg.objects.size(), 2U);
    EXPECT_EQ(cfg.objects[0].name, "table");
    EXPECT_EQ(cfg.objects[0].shapeType(), ShapeType::kPlane);
    EXPECT_TRUE(cfg.objects[0].isStatic());
    const SceneObject* block = cfg.findObject("block");
    ASSERT_NE(block, nullptr);
    ASSERT_EQ(block->shapeType(), ShapeType::kBox);
    EXPECT_EQ(std::get<BoxShape>(block->shape).half_extents_m, (Vec3{0.04, 0.03, 0.025}));
    EXPECT_EQ(block->pose.position_m, (Vec3{0.0, 0.0, 0.025}));
    EXPECT_DOUBLE_EQ(block->friction, 0.5);

    EXPECT_EQ(cfg.tracking.source, TrackingSource::kScripted);
    EXPECT_EQ(cfg.tracking.script, TrackingScript::kPressSlideEdge);
    EXPECT_EQ(cfg.tracking.target_object, "block");
    EXPECT_TRUE(cfg.tracking.loop);

    ASSERT_EQ(cfg.devices.size(), 2U);
    EXPECT_EQ(cfg.devices.at("exo").finger, Finger::kIndex);
    EXPECT_EQ(cfg.devices.at("thimble").finger, Finger::kIndex);
}

TEST(ShippedConfig, WholeHandSceneRunsAllFingersAtLevelZeroAt200Hz) {
    const SceneConfig cfg = loadSceneConfig(kConfigDir / "scenes/whole_hand.yaml");
    EXPECT_EQ(cfg.hand.model, HandModel::kHand);
    EXPECT_TRUE(cfg.hand.fingers.empty()) << "empty = all five fingers";
    EXPECT_EQ(cfg.hand.resolution, 0);
    EXPECT_EQ(cfg.rate_hz, 200);
    EXPECT_EQ(cfg.tracking.script, TrackingScript::kPressSlideEdge);
    EXPECT_NE(cfg.findObject("block"), nullptr);
    EXPECT_EQ(cfg.devices.size(), 2U);
}

TEST(ShippedConfig, ThimbleOnlyScene) {
    const SceneConfig cfg = loadSceneConfig(kConfigDir / "scenes/thimble_only.yaml");
    EXPECT_EQ(cfg.hand.model, HandModel::kFingertip);
    EXPECT_EQ(cfg.rate_hz, 200);
    EXPECT_EQ(cfg.devices.size(), 1U);
    EXPECT_TRUE(cfg.devices.contains("thimble"));
    EXPECT_EQ(cfg.objects[0].pose.rpy_rad, (Vec3{0.0, 0.0, 0.0}));  // rpy_deg defaults to zero
    // handsim's default budget, with the helper thread on.
    SolverLimits expected;
    expected.helper_thread = true;
    EXPECT_EQ(cfg.solver, expected);
}

TEST(ShippedConfig, GraspScene) {
    const SceneConfig cfg = loadSceneConfig(kConfigDir / "scenes/grasp_box.yaml");
    EXPECT_EQ(cfg.hand.model, HandModel::kHand);
    EXPECT_EQ(cfg.hand.fingers, (std::vector<Finger>{Finger::kThumb, Finger::kIndex}));
    EXPECT_TRUE(cfg.hand.simulates(Finger::kIndex));
    EXPECT_FALSE(cfg.hand.simulates(Finger::kMiddle));
    EXPECT_EQ(cfg.tracking.script, TrackingScript::kGraspLiftPlacePush);
    EXPECT_FALSE(cfg.tracking.loop);
    EXPECT_EQ(cfg.rate_hz, 200);  // the pinch did not hold at 60 Hz
    EXPECT_EQ(cfg.hand.resolution, 0);
    EXPECT_EQ(cfg.solver, SolverLimits{});  // handsim's default budget: 1 Newton, cap 30
    ASSERT_EQ(cfg.objects.size(), 3U);
    EXPECT_GT(cfg.objects[1].mass_kg, 0.0);  // both boxes are dynamic (Bullet moves them)
    EXPECT_GT(cfg.objects[2].mass_kg, 0.0);
}

TEST(ShippedConfig, RoudiHasAPoolForTheLargestMessage) {
    // msgs kMaxShmPayloadBytes: the largest iceoryx twin. Checked here by value so this test
    // does not depend on the msgs library.
    constexpr long kLargestPayloadBytes = 16384;
    std::ifstream in(kConfigDir / "roudi.toml");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("[general]"), std::string::npos);
    EXPECT_NE(text.find("version = 1"), std::string::npos);
    EXPECT_NE(text.find("[[segment]]"), std::string::npos);
    static const std::regex kSize(R"(\nsize = ([0-9]+)\ncount = ([0-9]+))");
    long largest = 0;
    int pools = 0;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), kSize);
         it != std::sregex_iterator(); ++it) {
        largest = std::max(largest, std::stol((*it)[1].str()));
        EXPECT_GT(std::stol((*it)[2].str()), 0);
        ++pools;
    }
    EXPECT_EQ(pools, 4);
    EXPECT_GE(largest, kLargestPayloadBytes);
}

TEST(ShippedConfig, DdsProfileIsLoopbackOnly) {
    std::ifstream in(kConfigDir / "dds_profiles.xml");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find(R"(profile_name="haptic_participant" is_default_profile="true")"),
              std::string::npos);
    EXPECT_NE(text.find("<useBuiltinTransports>false</useBuiltinTransports>"), std::string::npos);
    EXPECT_NE(text.find("<address>127.0.0.1</address>"), std::string::npos);
    EXPECT_NE(text.find("<initialPeersList>"), std::string::npos);
}

// --- test data that must load, so the malformed variants differ in one thing only ----------

TEST(ConfigTestData, LoadsAndCoversEveryShape) {
    EXPECT_NO_THROW((void)loadDaemonConfig(kDataDir / "daemon_ok.yaml"));
    const SimConfig sim = loadSimConfig(kDataDir / "sim_ok.yaml");
    EXPECT_EQ(sim.log_level, LogLevel::kDebug);
    EXPECT_EQ(sim.sim_link.transport, SimTransport::kDds);
    EXPECT_EQ(sim.dds.domain_id, 7);
    EXPECT_FALSE(sim.iceoryx.has_value());
    ASSERT_TRUE(sim.tracking_filter.has_value());
    EXPECT_EQ(sim.tracking_filter->min_cutoff_hz, 1.5);
    EXPECT_EQ(sim.tracking_filter->angle_beta_s_per_rad, std::optional<double>(8.0));
    EXPECT_EQ(sim.tracking_filter->position_beta_s_per_m, 40.0);
    EXPECT_EQ(sim.tracking_filter->derivative_cutoff_hz, 1.2);

    const SceneConfig& scene = sim.scene;
    ASSERT_EQ(scene.objects.size(), 4U);
    EXPECT_DOUBLE_EQ(scene.objects[1].mass_kg, 0.2);
    EXPECT_FALSE(scene.objects[1].isStatic());
    EXPECT_NEAR(scene.objects[1].pose.rpy_rad[2], std::numbers::pi / 2.0, kTol);
    EXPECT_DOUBLE_EQ(std::get<SphereShape>(scene.objects[2].shape).radius_m, 0.02);
    EXPECT_DOUBLE_EQ(scene.objects[2].friction, 0.5);  // default
    const auto& capsule = std::get<CapsuleShape>(scene.objects[3].shape);
    EXPECT_DOUBLE_EQ(capsule.radius_m, 0.01);
    EXPECT_DOUBLE_EQ(capsule.half_height_m, 0.05);
    EXPECT_DOUBLE_EQ(scene.hand.anthropometry.fingertip_diameter_m, 0.016);  // default

    EXPECT_NO_THROW((void)loadSceneConfig(kDataDir / "scenes/fingertip_ok.yaml"));
}

TEST(ConfigTestData, ASceneCanTurnTheSolversHelperThreadOn) {
    const SceneConfig cfg = loadSceneConfig(kDataDir / "scenes/solver_helper_thread_on.yaml");
    EXPECT_EQ(cfg.solver.newton_iterations, 2);
    EXPECT_TRUE(cfg.solver.helper_thread);
}

TEST(ConfigTestData, SameCanIdsOnDifferentInterfacesAreFine) {
    const DaemonConfig cfg = loadDaemonConfig(kDataDir / "daemon_two_buses.yaml");
    ASSERT_EQ(cfg.devices.size(), 2U);
    EXPECT_EQ(cfg.devices[0].can.command_id, cfg.devices[1].can.command_id);
    EXPECT_NE(cfg.devices[0].can.interface, cfg.devices[1].can.interface);
}

TEST(ConfigTestData, RelativeReferencesIgnoreTheWorkingDirectory) {
    const fs::path previous = fs::current_path();
    fs::current_path("/");
    const DaemonConfig from_root = loadDaemonConfig(kDataDir / "daemon_ok.yaml");
    fs::current_path(kDataDir / "devices");
    const DaemonConfig from_elsewhere = loadDaemonConfig("../daemon_ok.yaml");
    fs::current_path(previous);

    EXPECT_EQ(from_root.devices[1].source, resolved(kDataDir / "devices/thimble_ok.yaml"));
    EXPECT_EQ(from_elsewhere.devices[1].source, resolved(kDataDir / "devices/thimble_ok.yaml"));
    EXPECT_TRUE(from_elsewhere.devices[1].source.is_absolute());
}

}  // namespace
}  // namespace haptic::config

namespace haptic::config {
namespace {

// The digest names the bytes the daemon was configured from: stable across loads, changed by
// one byte of a device file, and the same for a copy elsewhere (paths are not hashed).
TEST(ConfigurationDigest, NamesTheBytesOfEveryFileTheDaemonRead) {
    const DaemonConfig shipped = loadDaemonConfig(test::kConfigDir / "daemon.yaml");
    const std::string digest = configurationDigest(shipped);
    EXPECT_TRUE(std::regex_match(digest, std::regex("sha256:[0-9a-f]{64}"))) << digest;
    EXPECT_EQ(configurationDigest(loadDaemonConfig(test::kConfigDir / "daemon.yaml")), digest);

    const std::filesystem::path copy =
        std::filesystem::temp_directory_path() / ("haptic-digest-" + std::to_string(::getpid()));
    std::filesystem::remove_all(copy);
    std::filesystem::copy(test::kConfigDir, copy, std::filesystem::copy_options::recursive);
    EXPECT_EQ(configurationDigest(loadDaemonConfig(copy / "daemon.yaml")), digest);
    {
        std::ofstream device(copy / "devices/thimble.yaml", std::ios::app);
        device << "\n";  // one byte, no change of meaning
    }
    EXPECT_NE(configurationDigest(loadDaemonConfig(copy / "daemon.yaml")), digest);
    const DaemonConfig changed = loadDaemonConfig(copy / "daemon.yaml");
    const auto expectRefusedNamingTheThimbleFile = [&changed](const char* what) {
        try {
            (void)configurationDigest(changed);
            ADD_FAILURE() << what << " was digested";
        } catch (const ConfigError& error) {
            EXPECT_NE(std::string(error.what()).find("thimble.yaml"), std::string::npos)
                << error.what();
        }
    };
    std::filesystem::remove(copy / "devices/thimble.yaml");
    expectRefusedNamingTheThimbleFile("a device file that is gone");
    // A directory where the file was opens as a stream and reads as nothing: refused too.
    std::filesystem::create_directory(copy / "devices/thimble.yaml");
    expectRefusedNamingTheThimbleFile("a directory in place of a device file");
    std::filesystem::remove_all(copy);
}

}  // namespace
}  // namespace haptic::config
