// Who may do what on hapticd's local control socket (docs/hapticctl.md#local-control), with
// real users of this host: hapticctl run as `daemon` (uid 1, outside the operator group) and
// as `nobody` (uid 65534, whose primary group `nogroup` is made the operator group here), via
// util-linux's setpriv. The socket lives in the directory control.socket_dir names (changed
// from the shipped /run/hapticd), so that key's effect is shown too. Over DDS only estop is
// taken, whoever sends it.

#include <sys/stat.h>

#include "device_safety_rig.hpp"

namespace haptic::testing {
namespace {

using ::testing::HasSubstr;

class ControlAccessTest : public DeviceSafetyTest {
  protected:
    ControlAccessTest() {
        replaceLine(config_.dir / "daemon.yaml", "socket_dir: /run/hapticd ",
                    "socket_dir: " + socketDir().string() + " ");
        replaceLine(config_.dir / "daemon.yaml", "operator_group: haptic ",
                    "operator_group: nogroup ");
    }

    fs::path socketDir() const { return config_.dir / "run"; }

    // hapticctl on the test's configuration, as `user` (uid:gid, no supplementary groups),
    // or as this process's user (root) when `user` is empty.
    CommandResult hapticctlAs(const std::string& user, std::vector<std::string> args) {
        std::vector<std::string> argv;
        if (!user.empty()) {
            const auto colon = user.find(':');
            argv = {"/usr/bin/setpriv", "--reuid=" + user.substr(0, colon),
                    "--regid=" + user.substr(colon + 1), "--clear-groups"};
        }
        for (const std::string& part :
             {std::string(HAPTICCTL_PATH), std::string("-c"),
              (config_.dir / "daemon.yaml").string(), std::string("--dds-domain"), domain(),
              std::string("--timeout"), std::string("10")}) {
            argv.push_back(part);
        }
        argv.insert(argv.end(), args.begin(), args.end());
        return runCommand(argv, 20s);
    }
};

constexpr const char* kOutsider = "1:1";        // daemon:daemon
constexpr const char* kMember = "65534:65534";  // nobody:nogroup

TEST_F(ControlAccessTest, OutsidersMayReadTheStatusAndStopButNotOperate) {
    const fs::path socket = socketDir() / ("control-" + domain() + ".sock");
    struct stat info {};
    ASSERT_EQ(::stat(socket.c_str(), &info), 0) << socket << " (control.socket_dir)";
    EXPECT_TRUE(S_ISSOCK(info.st_mode));

    // Anyone may read the status, over the socket (no DDS discovery in it).
    const CommandResult status = hapticctlAs(kOutsider, {"status"});
    EXPECT_EQ(status.exit_code, 0) << status.err;
    EXPECT_THAT(status.out, HasSubstr("State: IDLE"));

    const std::string method(
        waitForStatus("a status", [](const auto&) { return true; }).rendering_method.view());
    // Not enable, clear, disable or method: exit 2 with the reason.
    for (const std::vector<std::string>& command :
         {std::vector<std::string>{"enable"},
          {"clear"},
          {"disable"},
          {"method", method == "naive" ? "subspace" : "naive"}}) {
        const CommandResult refused = hapticctlAs(kOutsider, command);
        EXPECT_EQ(refused.exit_code, 2) << command[0] << ": " << refused.out << refused.err;
        EXPECT_THAT(refused.err,
                    HasSubstr("refused: uid 1 is not in group 'nogroup': only its members may "
                              "enable, disable, clear and choose the method"))
            << command[0];
    }
    EXPECT_THAT(daemon_->stderrText(), HasSubstr("local command 'enable' from uid 1 pid "));
    const auto idle = waitForStatus("still IDLE", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kIdle;
    });
    EXPECT_EQ(idle.rendering_method.view(), method) << "the refused method took effect";

    // A member through a supplementary group (the caller process's own, SO_PEERGROUPS):
    // uid 1 with nogroup added may operate; here it disables nothing, IDLE already.
    const CommandResult supplementary = runCommand(
        {"/usr/bin/setpriv", "--reuid=1", "--regid=1", "--groups=65534", HAPTICCTL_PATH, "-c",
         (config_.dir / "daemon.yaml").string(), "--dds-domain", domain(), "disable"},
        20s);
    EXPECT_EQ(supplementary.exit_code, 0) << supplementary.out << supplementary.err;

    // A member operates: enable, and the daemon renders.
    const CommandResult enabled = hapticctlAs(kMember, {"enable"});
    ASSERT_EQ(enabled.exit_code, 0) << enabled.out << enabled.err;
    waitForStatus("RENDERING after the member's enable", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kRendering;
    });
    EXPECT_THAT(daemon_->stderrText(), HasSubstr("local command 'enable' from uid 65534 pid "));

    // The outsider may always stop: E-STOP, which only a member's clear leaves.
    const CommandResult stopped = hapticctlAs(kOutsider, {"estop"});
    EXPECT_EQ(stopped.exit_code, 0) << stopped.out << stopped.err;
    waitForStatus("E-STOP after the outsider's estop",
                  [](const msgs::HapticStatus& s) { return s.state == msgs::DaemonState::kEstop; });
    EXPECT_EQ(hapticctlAs(kOutsider, {"clear"}).exit_code, 2);
    EXPECT_EQ(hapticctlAs(kMember, {"clear"}).exit_code, 0);
    waitForStatus("IDLE after the member's clear",
                  [](const msgs::HapticStatus& s) { return s.state == msgs::DaemonState::kIdle; });
}

// DDS carries no identity: whoever reaches the domain may stop the devices over
// haptic/command, and nothing else (as root here, who may do anything on the socket).
TEST_F(ControlAccessTest, OverDdsOnlyEstopIsTaken) {
    const CommandResult enable = hapticctlAs("", {"--over-dds", "enable"});
    EXPECT_EQ(enable.exit_code, 2) << enable.out << enable.err;
    EXPECT_THAT(enable.err, HasSubstr("over DDS only estop is taken"));
    const CommandResult status = hapticctlAs("", {"--over-dds", "status"});
    EXPECT_EQ(status.exit_code, 0) << status.err;
    EXPECT_THAT(status.out, HasSubstr("State: IDLE"));
    const CommandResult stopped = hapticctlAs("", {"--over-dds", "estop"});
    EXPECT_EQ(stopped.exit_code, 0) << stopped.out << stopped.err;
    waitForStatus("E-STOP after the estop over DDS",
                  [](const msgs::HapticStatus& s) { return s.state == msgs::DaemonState::kEstop; });
}

// A stop must get through: when the socket refuses the caller (here its permissions, as a
// misconfigured socket_dir would), hapticctl estop goes over DDS as well, and is taken.
TEST_F(ControlAccessTest, AnEstopTheSocketCannotCarryGoesOverDds) {
    const fs::path socket = socketDir() / ("control-" + domain() + ".sock");
    fs::permissions(socket, fs::perms::owner_read | fs::perms::owner_write);
    const CommandResult stopped = hapticctlAs(kOutsider, {"estop"});
    EXPECT_EQ(stopped.exit_code, 0) << stopped.out << stopped.err;
    EXPECT_THAT(stopped.err, HasSubstr("Permission denied"));
    EXPECT_THAT(stopped.err, HasSubstr("sending estop over DDS as well"));
    waitForStatus("E-STOP after the estop over DDS",
                  [](const msgs::HapticStatus& s) { return s.state == msgs::DaemonState::kEstop; });
    const CommandResult enable = hapticctlAs(kOutsider, {"enable"});
    EXPECT_NE(enable.exit_code, 0) << "no fallback for anything but estop";
}

// A second hapticd on the same domain finds the socket served and stops before it opens any
// device; a killed hapticd's socket file (nobody listening) is taken over by the next one.
TEST_F(ControlAccessTest, OneDaemonPerSocket) {
    const CommandResult second =
        runCommand({HAPTICD_PATH, "-c", (config_.dir / "daemon.yaml").string(), "--realtime",
                    "ignore", "--dds-domain", domain()},
                   20s);
    EXPECT_NE(second.exit_code, 0);
    EXPECT_THAT(second.err, HasSubstr("another hapticd serves it (one daemon per DDS domain)"));
    ASSERT_EQ(::kill(daemon_->pid(), SIGKILL), 0);
    (void)daemon_->waitFor(5s);
    ASSERT_TRUE(fs::exists(socketDir() / ("control-" + domain() + ".sock")))
        << "the killed hapticd's socket file";
    startDaemon();
    waitForStatus("IDLE again", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kIdle && s.devices.size() == 2;
    });
    const CommandResult status = hapticctlAs(kOutsider, {"status"});
    EXPECT_EQ(status.exit_code, 0) << status.err;
}

}  // namespace
}  // namespace haptic::testing
