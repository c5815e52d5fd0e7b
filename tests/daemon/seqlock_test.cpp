#include "haptic/daemon/seqlock.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
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

TEST(SeqLock, ReadersNeverSeeATornSnapshot) {
    SeqLock<Snapshot> sut;
    std::atomic<bool> done{false};
    std::thread writer([&] {
        Snapshot s;
        for (std::uint64_t i = 1; i <= 200000; ++i) {
            s.words.fill(i);
            sut.store(s);
        }
        done = true;
    });
    std::uint64_t reads = 0;
    std::uint64_t last = 0;
    while (!done) {
        Snapshot out;
        if (sut.load(out)) {
            for (auto word : out.words) {
                ASSERT_EQ(word, out.words[0]) << "torn read";
            }
            ASSERT_GE(out.words[0], last) << "went back in time";
            last = out.words[0];
            ++reads;
        }
    }
    writer.join();
    EXPECT_GT(reads, 0U);
}

}  // namespace
}  // namespace haptic::daemon
