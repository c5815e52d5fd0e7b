// The installed units' users (systemd/haptic.sysusers.conf, docs/systemd.md): RouDi and its
// clients as unprivileged users of one group, as the units run them (User=, Group=haptic-ipc),
// with the real iox-roudi, hapticd, handsim and hapticemu. Users of this host stand in, via
// util-linux's setpriv: RouDi as daemon (uid 1) with nogroup (65534) as its group, hapticd and
// handsim as nobody (65534, whose primary group in the user database is nogroup).
// iceoryx gives its shared memory and socket to RouDi's group, and takes a client's groups from
// the user database (its primary group there and /etc/group), not from the process: a client
// run as bin with nogroup by setpriv was refused ("no writable shared memory segment for the
// current user"). So the service users' primary group must be haptic-ipc in the user
// database, as haptic.sysusers.conf makes it (systemd_sysusers_dry_run checks).

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <sstream>

#include "device_safety_rig.hpp"

namespace haptic::testing {
namespace {

constexpr uid_t kRoudiUser = 1;        // daemon
constexpr uid_t kDaemonUser = 65534;   // nobody
constexpr uid_t kSimUser = 65534;      // nobody
constexpr gid_t kSharedGroup = 65534;  // nogroup

std::vector<std::string> asUser(uid_t uid) {
    return {"/usr/bin/setpriv", "--reuid=" + std::to_string(uid),
            "--regid=" + std::to_string(kSharedGroup), "--clear-groups"};
}

// The real uid and gid of a running process, from /proc/<pid>/status.
std::pair<long, long> idsOf(pid_t pid) {
    std::ifstream status("/proc/" + std::to_string(pid) + "/status");
    std::string line;
    long uid = -1;
    long gid = -1;
    while (std::getline(status, line)) {
        if (line.rfind("Uid:", 0) == 0) {
            uid = std::stol(line.substr(4));
        } else if (line.rfind("Gid:", 0) == 0) {
            gid = std::stol(line.substr(4));
        }
    }
    return {uid, gid};
}

// iceoryx's fixed paths (scripts/iceoryx-paths.sh, the one list), RouDi's group being
// nogroup here. After an unclean exit they stay owned by the user who ran RouDi or the
// client; with fs.protected_regular=2 (Debian 12's default) another user, root included,
// then cannot open them in /tmp. Removed before and after this test, while no RouDi runs.
void removeIceoryxLeftovers() {
    if (ipc::probeRoudi().reachable) {
        return;
    }
    const CommandResult paths =
        runCommand({"/bin/bash", HAPTIC_SOURCE_DIR "/scripts/iceoryx-paths.sh", "nogroup"}, 10s);
    ASSERT_EQ(paths.exit_code, 0) << paths.err;
    std::istringstream lines(paths.out);
    int removable = 0;
    for (std::string path; std::getline(lines, path);) {
        std::error_code ignored;
        fs::remove(path, ignored);
        ++removable;
    }
    EXPECT_GE(removable, 9) << "scripts/iceoryx-paths.sh listed: " << paths.out;
}

class ServiceUsersTest : public DeviceSafetyTest {
  protected:
    void SetUp() override {
        if (::geteuid() != 0 || ::access("/usr/bin/setpriv", X_OK) != 0) {
            GTEST_SKIP() << "needs root and util-linux's setpriv to run processes as other users";
        }
        // The stand-in users must reach the binaries (a build in a 0700 home is out of reach).
        const CommandResult reach =
            runCommand({"/usr/bin/setpriv", "--reuid=" + std::to_string(kDaemonUser),
                        "--regid=" + std::to_string(kSharedGroup), "--clear-groups", HAPTICD_PATH,
                        "--version"},
                       10s);
        if (reach.exit_code != 0) {
            GTEST_SKIP() << "user nobody cannot run " << HAPTICD_PATH << ": " << reach.err;
        }
        removeIceoryxLeftovers();
        DeviceSafetyTest::SetUp();
    }

    void TearDown() override {
        DeviceSafetyTest::TearDown();
        removeIceoryxLeftovers();
    }

    ServiceUsersTest() {
        roudi_launcher_ = asUser(kRoudiUser);
        daemon_launcher_ = asUser(kDaemonUser);
        sim_launcher_ = asUser(kSimUser);
        // hapticd reads its configuration as its own user and makes its control socket in a
        // directory that user owns, as RuntimeDirectory= gives it.
        fs::permissions(config_.dir, fs::perms::owner_all | fs::perms::group_read |
                                         fs::perms::group_exec | fs::perms::others_read |
                                         fs::perms::others_exec);
        const fs::path run = config_.dir / "run";
        fs::create_directories(run);
        EXPECT_EQ(::chown(run.c_str(), kDaemonUser, kSharedGroup), 0);
        fs::permissions(run, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                                 fs::perms::others_read | fs::perms::others_exec);
        replaceLine(config_.dir / "daemon.yaml", "socket_dir: /run/hapticd ",
                    "socket_dir: " + run.string() + " ");
        // A sanitized handsim steps at about 4 Hz: with the shipped 20 ms each of its targets
        // would render for a few ms at a fraction of the force before it fades again.
        if (HAPTIC_SANITIZED != 0) {
            replaceLine(config_.dir / "daemon.yaml", "sim_timeout_ms: 20", "sim_timeout_ms: 500");
        }
    }

    // hapticctl on this configuration, so over hapticd's control socket.
    void operate(const std::string& verb) {
        const CommandResult result =
            runCommand({HAPTICCTL_PATH, "-c", (config_.dir / "daemon.yaml").string(),
                        "--dds-domain", domain(), "--timeout", "10", verb},
                       20s);
        EXPECT_EQ(result.exit_code, 0)
            << verb << ": " << result.out << result.err << "hapticd log:\n"
            << daemon_->stderrText();
    }
};

TEST_F(ServiceUsersTest, RoudiAndItsClientsAsUnprivilegedUsersOfOneGroupRender) {
    ASSERT_FALSE(HasFatalFailure());
    EXPECT_EQ(idsOf(roudi_->pid()), std::make_pair(long{kRoudiUser}, long{kSharedGroup}));
    EXPECT_EQ(idsOf(daemon_->pid()), std::make_pair(long{kDaemonUser}, long{kSharedGroup}));
    // iceoryx's memory belongs to RouDi's user and group: 0660, no access for others.
    struct stat management {};
    ASSERT_EQ(::stat("/dev/shm/iceoryx_mgmt", &management), 0);
    EXPECT_EQ(management.st_uid, kRoudiUser);
    EXPECT_EQ(management.st_gid, kSharedGroup);
    EXPECT_EQ(management.st_mode & 0777U, 0660U) << std::oct << management.st_mode;

    startSim();
    waitForStatus("sim connected", [](const msgs::HapticStatus& s) {
        return s.sim_link.connected && s.sim_link.received > 20;
    });
    EXPECT_EQ(idsOf(sim_->pid()), std::make_pair(long{kSimUser}, long{kSharedGroup}));
    // Over the control socket hapticd made as its own user (root, running this test, operates).
    operate("enable");
    waitForStatus("RENDERING", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kRendering && s.sim_link.connected;
    });
    // The sim's targets reach the devices: the default scene presses the block within a
    // script period, and the exoskeleton renders it.
    double largest = 0.0;
    for (const auto& sample : collectTelemetry(kExo, 6500ms)) {
        largest = std::max(largest, std::abs(sample.exoskeleton.actuator_force_cmd_n));
    }
    std::printf("largest commanded exoskeleton force in 6.5 s: %.2f N\n", largest);
    EXPECT_GT(largest, 0.2) << "no force in a whole script period; hapticd log:\n"
                            << daemon_->stderrText() << "\nhandsim log:\n"
                            << sim_->stderrText();
    operate("disable");
}

}  // namespace
}  // namespace haptic::testing
