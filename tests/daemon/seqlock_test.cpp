#include "haptic/daemon/seqlock.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <iostream>
#include <thread>

namespace haptic::daemon {
namespace {

// Every word of a snapshot carries the same counter, so a torn read shows as a mix.
struct Snapshot {
    std::array<std::uint64_t, 64> words{};
};

TEST(SeqLock, LoadFailsBeforeTheFirstStore) {
    SeqLock<Snapshot> sut;
    Snapshot out;
    EXPECT_FALSE(sut.load(out));
}

// The writer stores, with short gaps, while the reader copies, until the reader has raced the
// writer often (tryLoad refused a copy: a store was under way or overlapped it) and taken many
// snapshots in between: only then is "no torn copy accepted" evidence. Bounded by time, not by
// a count of stores, so a loaded machine (one core shared by both threads) only takes longer.
TEST(SeqLock, ReadersNeverSeeATornSnapshot) {
    SeqLock<Snapshot> sut;
    std::atomic<bool> stop{false};
    std::thread writer([&] {
        Snapshot s;
        for (std::uint64_t i = 1; !stop.load(std::memory_order_relaxed); ++i) {
            s.words.fill(i);
            sut.store(s);
            // Gaps of varying length between the stores, so that reads both overlap stores
            // and fall between them (back to back, a sanitized reader almost never copies
            // a whole snapshot between two stores).
            for (std::uint64_t spin = 0; spin < (i % 32) * 16; ++spin) {
                (void)stop.load(std::memory_order_relaxed);
            }
        }
    });
    constexpr std::uint64_t kEnoughRaces = 10000;
    constexpr std::uint64_t kEnoughReads = 10000;
    std::uint64_t reads = 0;
    std::uint64_t raced = 0;
    std::uint64_t last = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while ((raced < kEnoughRaces || reads < kEnoughReads) &&
           std::chrono::steady_clock::now() < deadline) {
        Snapshot out;
        const std::uint64_t version = sut.tryLoad(out);
        if (version == 0) {
            raced += sut.version() > 0 ? 1 : 0;
            continue;
        }
        for (auto word : out.words) {
            ASSERT_EQ(word, out.words[0]) << "torn read accepted, version " << version;
        }
        EXPECT_EQ(out.words[0], version) << "the version names the store it copied";
        ASSERT_GE(out.words[0], last) << "went back in time";
        last = out.words[0];
        ++reads;
    }
    stop = true;
    writer.join();
    std::cout << reads << " snapshots taken, " << raced << " copies refused\n";
    EXPECT_GE(raced, kEnoughRaces) << "copies refused: a store under way or overlapping";
    EXPECT_GE(reads, kEnoughReads) << "snapshots taken while the writer ran";
    Snapshot out;
    ASSERT_TRUE(sut.load(out));
    EXPECT_EQ(out.words[0], sut.version()) << "the last store, whole";
}

}  // namespace
}  // namespace haptic::daemon
