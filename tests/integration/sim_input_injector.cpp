// sim_input_injector: plays a 100 Hz sim for device_safety_test over iceoryx, with bad
// messages on request. The exoskeleton gets a wall it is always inside, the thimble a flat
// object 0.5 mm into its pad. stdin: "bad on" adds, 5 ms after every good pair, one bad
// ConstraintSet and one bad ContactSurface (each way a message can be bad, in turn);
// "bad off" stops them and prints "sent <count>". Old content, sent on as usual every 10 ms:
// "replay" publishes the last good pair again, header and all; "delay <ms>" stamps each new
// pair <ms> before it is sent (as if it had been that long on its way); "fresh" ends either.
// Prints "ready" once hapticd subscribed.
// A separate process because RouDi signals every registered process when it stops.

#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <limits>
#include <string>
#include <thread>

#include "haptic/ipc/iceoryx_channels.hpp"
#include "haptic/ipc/iceoryx_runtime.hpp"
#include "haptic/ipc/topics.hpp"
#include "haptic/msgs/messages.hpp"
#include "haptic/process/shutdown.hpp"
#include "iceoryx_posh/popo/publisher.hpp"

namespace {

using namespace haptic;
using namespace std::chrono_literals;

std::int64_t monotonicNs() {
    timespec ts{};
    ::clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// A wall at MCP <= -0.4 rad, beyond the joint's limit: the emulated finger is always inside
// it, so the exoskeleton renders force while this input is fresh.
msgs::ConstraintSet wallConstraintSet(std::uint64_t seq) {
    msgs::ConstraintSet message;
    message.header.seq = seq;
    message.header.stamp_ns = monotonicNs();
    message.header.source_id.assign("exo");
    message.dof = 3;
    msgs::LinearConstraint wall;
    wall.a = {-1.0, 0.0, 0.0};
    wall.b = 0.4;
    message.constraints.push_back(wall);
    return message;
}

// A flat object 0.5 mm into the thimble's pad (64 samples): the optimiser's answer, and so
// the thimble's servo targets, depend on nothing else.
msgs::ContactSurface flatContact(std::uint64_t seq) {
    msgs::ContactSurface message;
    message.header.seq = seq;
    message.header.stamp_ns = monotonicNs();
    message.header.source_id.assign("thimble");
    for (int i = 0; i < 8; ++i) {
        for (int j = 0; j < 8; ++j) {
            msgs::ContactSample sample;
            sample.p_device_m = {-0.0035 + 0.001 * i, -0.0035 + 0.001 * j, 0.017};
            sample.signed_distance_m = -0.0005;
            sample.normal_device = {0.0, 0.0, -1.0};
            sample.weight = 1e-6;
            message.samples.push_back(sample);
        }
    }
    return message;
}

// Each way a message can be bad, in turn: NaN, Inf, wrong dof, zero normal, over capacity.
msgs::ConstraintSet badConstraintSet(std::uint64_t seq, int kind) {
    msgs::ConstraintSet message = wallConstraintSet(seq);
    switch (kind % 5) {
        case 0:
            message.q_sim_rad[1] = std::numeric_limits<double>::quiet_NaN();
            break;
        case 1:
            message.constraints[0].a[0] = std::numeric_limits<double>::infinity();
            break;
        case 2:
            message.dof = 7;  // the exoskeleton has 3 joints
            break;
        case 3:
            message.constraints[0].a = {};
            break;
        default:
            message.constraints.count = msgs::kMaxConstraints + 1;
            break;
    }
    return message;
}

// NaN, non-unit normal, negative weight, another device's id, over capacity.
msgs::ContactSurface badContact(std::uint64_t seq, int kind) {
    msgs::ContactSurface message = flatContact(seq);
    switch (kind % 5) {
        case 0:
            message.samples[3].p_device_m[2] = std::numeric_limits<double>::quiet_NaN();
            break;
        case 1:
            message.samples[5].normal_device = {0.0, 0.0, -2.0};
            break;
        case 2:
            message.samples[7].weight = -1.0;
            break;
        case 3:
            message.header.source_id.assign("exo");
            break;
        default:
            message.samples.count = msgs::kMaxContactSamples + 1;
            break;
    }
    return message;
}

// The next complete stdin line, if one is waiting.
bool readLine(std::string& pending, std::string& line) {
    pollfd fd{STDIN_FILENO, POLLIN, 0};
    if (::poll(&fd, 1, 0) > 0 && (fd.revents & POLLIN) != 0) {
        char buffer[256];
        const ssize_t count = ::read(STDIN_FILENO, buffer, sizeof(buffer));
        if (count > 0) {
            pending.append(buffer, static_cast<std::size_t>(count));
        }
    }
    const auto newline = pending.find('\n');
    if (newline == std::string::npos) {
        return false;
    }
    line = pending.substr(0, newline);
    pending.erase(0, newline + 1);
    return true;
}

}  // namespace

int main() {
    process::installShutdownHandlers();
    ipc::initIceoryxRuntime("sim_input_injector");
    iox::popo::Publisher<msgs::ConstraintSet> constraints(
        ipc::deviceService("exo", ipc::kConstraintSetEvent));
    iox::popo::Publisher<msgs::ContactSurface> contacts(
        ipc::deviceService("thimble", ipc::kContactSurfaceEvent));
    while (!constraints.hasSubscribers() || !contacts.hasSubscribers()) {
        if (process::shutdownRequested()) {
            return 1;
        }
        std::this_thread::sleep_for(10ms);
    }
    std::printf("ready\n");
    std::fflush(stdout);

    std::uint64_t seq = 0;
    std::uint64_t bad_sent = 0;
    int kind = 0;
    bool bad = false;
    bool replay = false;
    std::int64_t delay_ns = 0;
    msgs::ConstraintSet last_constraints = wallConstraintSet(0);
    msgs::ContactSurface last_contact = flatContact(0);
    std::string pending;
    std::string line;
    while (!process::shutdownRequested()) {
        if (!replay) {
            ++seq;
            last_constraints = wallConstraintSet(seq);
            last_contact = flatContact(seq);
            last_constraints.header.stamp_ns -= delay_ns;
            last_contact.header.stamp_ns -= delay_ns;
        }
        constraints.loan().and_then([&](auto& sample) {
            *sample = last_constraints;
            sample.publish();
        });
        contacts.loan().and_then([&](auto& sample) {
            *sample = last_contact;
            sample.publish();
        });
        // hapticd takes one message per tick from a queue of one: 5 ms apart, none is lost.
        std::this_thread::sleep_for(5ms);
        if (bad) {
            constraints.loan().and_then([&](auto& sample) {
                *sample = badConstraintSet(seq, kind);
                sample.publish();
                ++bad_sent;
            });
            contacts.loan().and_then([&](auto& sample) {
                *sample = badContact(seq, kind);
                sample.publish();
                ++bad_sent;
            });
            ++kind;
        }
        std::this_thread::sleep_for(5ms);
        while (readLine(pending, line)) {
            if (line == "bad on") {
                bad = true;
                bad_sent = 0;
            } else if (line == "replay") {
                replay = true;
            } else if (line.rfind("delay ", 0) == 0) {
                delay_ns = std::stoll(line.substr(6)) * 1'000'000;
            } else if (line == "fresh") {
                replay = false;
                delay_ns = 0;
            } else if (line == "bad off") {
                bad = false;
                std::printf("sent %llu\n", static_cast<unsigned long long>(bad_sent));
                std::fflush(stdout);
            }
        }
    }
    return 0;
}
