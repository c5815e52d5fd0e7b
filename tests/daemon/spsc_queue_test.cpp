#include "haptic/daemon/spsc_queue.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>

#include "haptic/daemon/command_channel.hpp"

namespace haptic::daemon {
namespace {

// Every word carries the same counter, so a sample copied while it was written shows as a mix.
struct Sample {
    std::array<std::uint64_t, 32> words{};
};

// The RT thread's telemetry direction: a producer that never waits (a full queue refuses the
// push, counted) and a consumer draining it. Small capacity, so the ring wraps thousands of
// times: under ThreadSanitizer that is the slot reuse iceoryx's queues leave unordered.
TEST(SpscQueue, EverySampleArrivesWholeAndInOrderOrIsCountedAsRefused) {
    SpscQueue<Sample, 64> queue;
    constexpr std::uint64_t kSamples = 200000;
    std::uint64_t refused = 0;
    std::atomic<bool> done{false};
    std::thread producer([&] {
        Sample sample;
        for (std::uint64_t i = 1; i <= kSamples; ++i) {
            sample.words.fill(i);
            refused += queue.push(sample) ? 0 : 1;
        }
        done = true;
    });
    std::uint64_t received = 0;
    std::uint64_t last = 0;
    std::uint64_t torn = 0;
    std::uint64_t out_of_order = 0;
    Sample out;
    // `done` is read before the pop: once it is seen true, an empty queue stays empty.
    // (Counted, not asserted, here: the producer must be joined before the test can end.)
    for (bool finished = false; !finished;) {
        finished = done;
        while (queue.pop(out)) {
            for (const auto word : out.words) {
                torn += word != out.words[0] ? 1 : 0;
            }
            out_of_order += out.words[0] > last ? 0 : 1;
            last = out.words[0];
            ++received;
        }
    }
    producer.join();
    EXPECT_EQ(torn, 0U) << "a sample copied while it was written";
    EXPECT_EQ(out_of_order, 0U) << "out of order or repeated";
    EXPECT_EQ(received + refused, kSamples);
    EXPECT_GT(received, 0U);
}

// Both directions of the command channel at once, each with one thread on either end.
TEST(CommandChannel, CommandsAndRepliesCrossBetweenTwoThreads) {
    CommandChannel channel;
    constexpr std::uint32_t kCommands = 20000;
    std::thread rt([&] {
        msgs::HapticCommand command;
        std::uint32_t handled = 0;
        while (handled < kCommands) {
            if (channel.takeCommand(command)) {
                msgs::HapticCommandReply reply;
                reply.request_id = command.request_id;
                while (!channel.postReply(reply)) {
                    std::this_thread::yield();
                }
                ++handled;
            }
        }
    });
    std::uint32_t sent = 0;
    std::uint32_t replied = 0;
    msgs::HapticCommandReply reply;
    while (replied < kCommands) {
        if (sent < kCommands) {
            msgs::HapticCommand command;
            command.request_id = sent + 1;
            if (channel.submit(command)) {
                ++sent;
            }
        }
        while (channel.takeReply(reply)) {
            ++replied;
            EXPECT_EQ(reply.request_id, replied) << "replies in the order of the commands";
        }
    }
    rt.join();
}

}  // namespace
}  // namespace haptic::daemon
