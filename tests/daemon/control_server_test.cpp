// The control socket's server in one thread: the test is the caller (raw SOCK_SEQPACKET, so
// each step is explicit), hapticd's main thread (serve(), deliver()) and the RT thread
// (taking the command from the channel and posting its reply) in turn. As root, which may
// operate; who else may is ControlAccessTest's (device_safety_test, real users).

#include "haptic/control/control_server.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "haptic/control/log_limit.hpp"
#include "haptic/msgs/conversions.hpp"

namespace haptic::control {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using ::testing::HasSubstr;

class ControlServerTest : public ::testing::Test {
  protected:
    ControlServerTest()
        : dir_(fs::temp_directory_path() / ("haptic-control-" + std::to_string(::getpid()))),
          socket_(dir_ / "run" / "control-0.sock") {
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    ~ControlServerTest() override { fs::remove_all(dir_); }

    int connectCaller() {
        const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
        sockaddr_un address{};
        address.sun_family = AF_UNIX;
        std::strncpy(address.sun_path, socket_.c_str(), sizeof(address.sun_path) - 1);
        EXPECT_EQ(::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0)
            << std::strerror(errno);
        return fd;
    }

    // Sends `datagram`, lets the server accept and serve, and returns what came back (empty:
    // nothing yet).
    std::vector<char> exchange(ControlServer& server, int fd, const std::vector<char>& datagram) {
        EXPECT_EQ(::send(fd, datagram.data(), datagram.size(), 0),
                  static_cast<ssize_t>(datagram.size()));
        server.serve(10ms);  // accepts
        server.serve(10ms);  // serves
        return receive(fd);
    }

    static std::vector<char> receive(int fd) {
        std::vector<char> buffer(kMaxDatagram);
        const ssize_t n = ::recv(fd, buffer.data(), buffer.size(), MSG_DONTWAIT);
        buffer.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
        return buffer;
    }

    // The seq of the status an answer carries; 0 (after a failure) when it carries none.
    static std::uint64_t statusSeqOf(const std::vector<char>& answer) {
        idl::HapticStatus status;
        if (answer.empty() || answer[0] != kStatusAnswer ||
            !decode(answer.data() + 1, answer.size() - 1, status)) {
            ADD_FAILURE() << "no status in an answer of " << answer.size() << " bytes";
            return 0;
        }
        return status.header().seq();
    }

    // A snapshot numbered `seq`, taken by the RT thread at `taken_ns` (default: seq ms).
    static idl::HapticStatus statusNumbered(std::uint64_t seq, std::int64_t taken_ns = -1) {
        msgs::HapticStatus status;
        status.header.seq = seq;
        status.header.stamp_ns =
            taken_ns >= 0 ? taken_ns : static_cast<std::int64_t>(seq) * 1'000'000;
        status.state = msgs::DaemonState::kIdle;
        return msgs::toIdl(status);
    }

    static std::vector<char> commandDatagram(msgs::CommandKind kind, std::uint64_t request_id) {
        msgs::HapticCommand command;
        command.request_id = request_id;
        command.kind = kind;
        std::vector<char> datagram;
        EXPECT_TRUE(encode(kCommandRequest, msgs::toIdl(command), datagram));
        return datagram;
    }

    // Why a server on socket_ could not be made ("" when it could: then it is gone again).
    std::string whyNoServer() {
        daemon::CommandChannel channel;
        try {
            const ControlServer server(socket_, "haptic", channel);
        } catch (const std::runtime_error& error) {
            return error.what();
        }
        return "";
    }

    fs::path dir_;
    fs::path socket_;
    daemon::CommandChannel channel_;
};

TEST_F(ControlServerTest, AnswersTheStatusItWasGivenAndNothingBefore) {
    ControlServer server(socket_, "haptic", channel_);
    EXPECT_EQ(fs::status(socket_.parent_path()).permissions() & fs::perms::all,
              fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                  fs::perms::others_read | fs::perms::others_exec);
    const int fd = connectCaller();
    std::vector<char> answer = exchange(server, fd, {kStatusRequest});
    ASSERT_FALSE(answer.empty());
    EXPECT_EQ(answer[0], kErrorAnswer);
    EXPECT_EQ(std::string(answer.begin() + 1, answer.end()),
              "no status yet (the loop is starting)");

    server.publish(statusNumbered(42));
    EXPECT_EQ(statusSeqOf(exchange(server, fd, {kStatusRequest})), 42U);
    ::close(fd);
}

// The command reaches the channel under a local request id; the RT thread's reply goes back
// to the caller under the caller's own id; a status asked for after it waits for a snapshot
// taken after the tick that applied it (one taken before would show the state before it).
TEST_F(ControlServerTest, ACommandGoesToTheRtThreadAndItsReplyBackToTheCaller) {
    ControlServer server(socket_, "haptic", channel_);
    server.publish(statusNumbered(1));
    const int fd = connectCaller();
    EXPECT_TRUE(exchange(server, fd, commandDatagram(msgs::CommandKind::kEstop, 77)).empty())
        << "no answer before the RT thread's";
    EXPECT_TRUE(server.awaitingReplies());

    msgs::HapticCommand taken;
    ASSERT_TRUE(channel_.takeCommand(taken));  // the RT thread
    EXPECT_EQ(taken.kind, msgs::CommandKind::kEstop);
    EXPECT_NE(taken.request_id & ControlServer::kLocalRequestBit, 0U);
    msgs::HapticCommandReply reply;
    reply.request_id = taken.request_id;
    reply.accepted = true;
    reply.message.assign("emergency stop");
    reply.header.stamp_ns = 1'500'000;  // the RT tick that applied it
    ASSERT_TRUE(channel_.postReply(reply));

    msgs::HapticCommandReply other = reply;
    other.request_id = 5;  // a DDS caller's
    EXPECT_FALSE(server.deliver(other));
    msgs::HapticCommandReply answered;
    ASSERT_TRUE(channel_.takeReply(answered));
    EXPECT_TRUE(server.deliver(answered));
    EXPECT_FALSE(server.awaitingReplies());
    std::vector<char> answer = receive(fd);
    ASSERT_FALSE(answer.empty());
    ASSERT_EQ(answer[0], kReplyAnswer);
    idl::HapticCommandReply wire;
    ASSERT_TRUE(decode(answer.data() + 1, answer.size() - 1, wire));
    EXPECT_EQ(wire.request_id(), 77U);
    EXPECT_TRUE(wire.accepted());

    EXPECT_TRUE(exchange(server, fd, {kStatusRequest}).empty()) << "the snapshot predates it";
    // A snapshot taken before that tick, published late by the main thread, is not enough.
    server.publish(statusNumbered(7, 1'200'000));
    EXPECT_TRUE(receive(fd).empty()) << "answered with a snapshot from before the command";
    server.publish(statusNumbered(2));
    EXPECT_EQ(statusSeqOf(receive(fd)), 2U);
    ::close(fd);
}

TEST_F(ControlServerTest, AMalformedCommandIsAnsweredAndNeverReachesTheRtThread) {
    ControlServer server(socket_, "haptic", channel_);
    const int fd = connectCaller();
    const std::vector<char> answer = exchange(server, fd, {kCommandRequest, 1, 2, 3});
    ASSERT_FALSE(answer.empty());
    EXPECT_EQ(answer[0], kErrorAnswer);
    msgs::HapticCommand taken;
    EXPECT_FALSE(channel_.takeCommand(taken));
    ::close(fd);
}

// A user flooding the socket with malformed commands gets every one answered, and 5 of them
// in the journal (the rest are summed up once its 10 s are over: PerUidLogLimit below).
TEST_F(ControlServerTest, AFloodOfBadCommandsIsAnsweredButLoggedFiveTimes) {
    std::ostringstream journal;
    // The default logger writes into `journal` for this test only, however it ends.
    struct CaptureLog {
        std::shared_ptr<spdlog::logger> previous = spdlog::default_logger();
        explicit CaptureLog(std::ostringstream& to) {
            spdlog::set_default_logger(std::make_shared<spdlog::logger>(
                "capture", std::make_shared<spdlog::sinks::ostream_sink_mt>(to)));
        }
        ~CaptureLog() { spdlog::set_default_logger(previous); }
    };
    {
        const CaptureLog capture(journal);
        ControlServer server(socket_, "haptic", channel_);
        const int fd = connectCaller();
        int answered = 0;
        for (int i = 0; i < 20; ++i) {
            const std::vector<char> answer = exchange(server, fd, {kCommandRequest, 1, 2, 3});
            answered += !answer.empty() && answer[0] == kErrorAnswer;
        }
        EXPECT_EQ(answered, 20);
        ::close(fd);
    }
    const std::string text = journal.str();
    std::size_t lines = 0;
    for (std::size_t at = text.find(": malformed"); at != std::string::npos;
         at = text.find(": malformed", at + 1)) {
        ++lines;
    }
    EXPECT_EQ(lines, 5U) << text;
}

TEST(PerUidLogLimit, LogsTheFirstLinesOfAWindowAndSumsUpTheRest) {
    using Clock = PerUidLogLimit::Clock;
    PerUidLogLimit limit(3, std::chrono::seconds(10));
    const Clock::time_point t0{};
    int logged = 0;
    for (int i = 0; i < 8; ++i) {
        logged += limit.admit(1000, t0 + std::chrono::milliseconds(i)) ? 1 : 0;
    }
    EXPECT_EQ(logged, 3);
    EXPECT_TRUE(limit.admit(1001, t0)) << "another user has lines of its own";
    EXPECT_TRUE(limit.expired(t0 + std::chrono::seconds(9)).empty()) << "the window is not over";
    const auto summary = limit.expired(t0 + std::chrono::seconds(10));
    ASSERT_EQ(summary.size(), 1U) << "uid 1001 logged all it had: nothing to sum up";
    EXPECT_EQ(summary[0].first, 1000U);
    EXPECT_EQ(summary[0].second, 5U);
    EXPECT_TRUE(limit.admit(1000, t0 + std::chrono::seconds(11))) << "a new window";
}

// One user opening connections without end keeps its newest 16; the others are closed.
TEST_F(ControlServerTest, AUserKeepsItsNewestConnectionsOnly) {
    ControlServer server(socket_, "haptic", channel_);
    server.publish(statusNumbered(3));
    std::vector<int> fds;
    for (int i = 0; i < 20; ++i) {
        fds.push_back(connectCaller());
        server.serve(10ms);
    }
    for (int i = 0; i < 20; ++i) {
        char byte = 0;
        const ssize_t n = ::recv(fds[static_cast<std::size_t>(i)], &byte, 1, MSG_DONTWAIT);
        if (i < 4) {
            EXPECT_EQ(n, 0) << "connection " << i << " should have been closed";
        } else {
            EXPECT_EQ(n, -1) << "connection " << i << " should be open";
        }
    }
    const std::vector<char> answer = exchange(server, fds.back(), {kStatusRequest});
    ASSERT_FALSE(answer.empty());
    EXPECT_EQ(answer[0], kStatusAnswer);
    for (const int fd : fds) {
        ::close(fd);
    }
}

// A socket file left by a killed hapticd is replaced; a served one, or any other file, is not.
TEST_F(ControlServerTest, AStaleSocketIsReplacedAndALiveOneOrAnotherFileIsNot) {
    fs::create_directories(socket_.parent_path());
    {
        // What a SIGKILLed hapticd leaves: a bound socket file nobody listens on.
        const int dead = ::socket(AF_UNIX, SOCK_SEQPACKET, 0);
        sockaddr_un address{};
        address.sun_family = AF_UNIX;
        std::strncpy(address.sun_path, socket_.c_str(), sizeof(address.sun_path) - 1);
        ASSERT_EQ(::bind(dead, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0);
        ::close(dead);
    }
    {
        ControlServer first(socket_, "haptic", channel_);
        EXPECT_TRUE(fs::is_socket(socket_));
        const int fd = connectCaller();
        ::close(fd);
        EXPECT_THAT(whyNoServer(), HasSubstr("another hapticd serves it"))
            << "a second server took a live socket";
        EXPECT_TRUE(fs::is_socket(socket_)) << "the refused one left the live socket alone";
    }
    EXPECT_FALSE(fs::exists(socket_)) << "removed when its server stops";
    std::ofstream(socket_) << "someone's file";
    EXPECT_THAT(whyNoServer(), HasSubstr("exists and is not a socket"))
        << "a regular file was replaced";
    EXPECT_TRUE(fs::is_regular_file(socket_));
}

// A directory others may write to could hold someone else's socket in hapticd's place.
TEST_F(ControlServerTest, ADirectoryOthersMayWriteToIsRefused) {
    fs::create_directories(socket_.parent_path());
    fs::permissions(socket_.parent_path(), fs::perms::all);
    EXPECT_THAT(whyNoServer(), HasSubstr("others cannot write to"))
        << "took a world-writable directory";
}

}  // namespace
}  // namespace haptic::control
