// hapticd's DDS sim link in one process: a real Fast DDS participant on a test-only domain
// writes per-device messages; the link's thread hands them to the RT-side take functions.

#include "dds_sim_link.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "allocation_counter.hpp"
#include "haptic/daemon/seqlock.hpp"
#include "haptic/daemon/sim_input_validation.hpp"
#include "haptic/ipc/topics.hpp"
#include "haptic/msgs/conversions.hpp"

namespace haptic::hapticd {
namespace {

using namespace std::chrono_literals;

ipc::DdsSettings testSettings() {
    // The shipped UDP-loopback profile on a domain of our own: 230-232 is used by no other test
    // (the process tests take 100-199, the loop benchmark 200-229, the demo 0), since this
    // test may run beside them; its own tests run one at a time (a resource lock). Domains
    // 1-99 had their ports (7400 + 250 d ...) inside the UDP blocks other tests bind
    // (10000-31699).
    return ipc::DdsSettings{static_cast<std::uint32_t>(230 + ::getpid() % 3),
                            HAPTIC_CONFIG_DIR "/dds_profiles.xml", "haptic_participant"};
}

msgs::ConstraintSet constraintSet(std::uint64_t seq) {
    msgs::ConstraintSet message{};
    message.header.seq = seq;
    message.header.stamp_ns = static_cast<std::int64_t>(seq) * 1000;
    message.header.source_id.assign("exo");
    return message;
}

msgs::ContactSurface contactSurface(std::uint64_t seq) {
    msgs::ContactSurface message{};
    message.header.seq = seq;
    message.header.source_id.assign("thimble");
    return message;
}

class DdsSimLinkTest : public ::testing::Test {
  protected:
    DdsSimLinkTest()
        : participant_(testSettings(), "dds_sim_link_test"),
          link_(participant_,
                {{"exo", msgs::DeviceKind::kExoskeleton}, {"thimble", msgs::DeviceKind::kThimble}}),
          constraint_writer_(participant_.createWriter<idl::ConstraintSetPubSubType>(
              ipc::deviceTopic(ipc::kConstraintSetTopic, "exo"), ipc::TopicKind::kLatestState)),
          surface_writer_(participant_.createWriter<idl::ContactSurfacePubSubType>(
              ipc::deviceTopic(ipc::kContactSurfaceTopic, "thimble"),
              ipc::TopicKind::kLatestState)),
          state_reader_(participant_.createReader<idl::DeviceStatePubSubType>(
              ipc::deviceTopic(ipc::kDeviceStateTopic, "thimble"), ipc::TopicKind::kLatestState)) {
        link_.start();
    }

    // Publishes once the link's reader has matched (reliable from then on) and waits for the
    // RT side to take it; returns the message taken, or nullptr after 10 s.
    const msgs::ConstraintSet* publishAndTake(std::uint64_t seq) {
        const auto deadline = std::chrono::steady_clock::now() + 10s;
        while (constraint_writer_.matchedReaders() == 0 &&
               std::chrono::steady_clock::now() < deadline) {
            std::this_thread::sleep_for(1ms);
        }
        constraint_writer_.write(msgs::toIdl(constraintSet(seq)));
        while (std::chrono::steady_clock::now() < deadline) {
            if (const auto* taken = link_.takeConstraintSet(0)) {
                return taken;
            }
            std::this_thread::sleep_for(1ms);
        }
        return nullptr;
    }

    ipc::DdsParticipant participant_;
    DdsSimLink link_;
    ipc::DdsWriter<idl::ConstraintSet> constraint_writer_;
    ipc::DdsWriter<idl::ContactSurface> surface_writer_;
    ipc::DdsReader<idl::DeviceState> state_reader_;
};

TEST_F(DdsSimLinkTest, DeliversEachDevicesNewestMessageOnceToTheRtSide) {
    const auto* taken = publishAndTake(7);
    ASSERT_NE(taken, nullptr) << "no ConstraintSet arrived over DDS within 10 s";
    EXPECT_EQ(taken->header.seq, 7U);
    EXPECT_EQ(taken->header.source_id.view(), "exo");
    EXPECT_EQ(link_.takeConstraintSet(0), nullptr) << "the same message must not be taken twice";
    EXPECT_EQ(link_.takeContactSurface(0), nullptr) << "the exoskeleton has no contact surface";
    EXPECT_EQ(link_.takeContactSurface(1), nullptr) << "nothing was sent to the thimble";

    for (int i = 0; i < 10000 && surface_writer_.matchedReaders() == 0; ++i) {
        std::this_thread::sleep_for(1ms);
    }
    surface_writer_.write(msgs::toIdl(contactSurface(3)));
    const msgs::ContactSurface* surface = nullptr;
    for (int i = 0; i < 5000 && surface == nullptr; ++i) {
        surface = link_.takeContactSurface(1);
        std::this_thread::sleep_for(1ms);
    }
    ASSERT_NE(surface, nullptr);
    EXPECT_EQ(surface->header.seq, 3U);
    EXPECT_GE(link_.received(0), 1U);
    EXPECT_EQ(link_.received(1), 1U);
}

// A sim of another release over DDS: its message fits no twin, so the link logs it and counts
// it unconvertible, but hands it on for its header, which says the other schema; the RT side
// then refuses it as other_schema, and the status shows it.
TEST_F(DdsSimLinkTest, AMessageOfAnotherSchemaGoesOnForItsHeaderAlone) {
    ASSERT_NE(publishAndTake(1), nullptr) << "no ConstraintSet arrived over DDS within 10 s";
    idl::ConstraintSet other = msgs::toIdl(constraintSet(2));
    other.header().schema(1);  // the release before the field: its seq read as the schema
    constraint_writer_.write(other);
    const msgs::ConstraintSet* taken = nullptr;
    for (int i = 0; i < 10000 && taken == nullptr; ++i) {
        taken = link_.takeConstraintSet(0);
        std::this_thread::sleep_for(1ms);
    }
    ASSERT_NE(taken, nullptr);
    EXPECT_EQ(taken->header.schema, 1U);
    EXPECT_EQ(taken->header.seq, 2U);
    EXPECT_EQ(daemon::validate(*taken, "exo", 3), daemon::InputRejection::kOtherSchema);
    EXPECT_EQ(link_.unconvertible(), 1U);
    EXPECT_EQ(link_.received(0), 1U) << "counted as received only in this release's schema";
}

TEST_F(DdsSimLinkTest, RtSideNeitherAllocatesNorBlocks) {
    ASSERT_NE(publishAndTake(1), nullptr);
    msgs::DeviceState state{};
    state.header.source_id.assign("thimble");
    std::uint64_t taken = 0;
    std::uint64_t allocations = 0;
    {
        testing::ScopedAllocationCounter counter;
        for (std::uint64_t tick = 0; tick < 10000; ++tick) {
            taken += link_.takeConstraintSet(0) != nullptr ? 1 : 0;
            taken += link_.takeContactSurface(1) != nullptr ? 1 : 0;
            state.header.seq = tick;
            link_.storeDeviceState(0, state);
            link_.storeDeviceState(1, state);
        }
        allocations = counter.allocations();
    }
    EXPECT_EQ(allocations, 0U);
    EXPECT_EQ(taken, 0U) << "nothing new was published";
}

TEST_F(DdsSimLinkTest, PublishesTheNewestDeviceStateForTheSim) {
    msgs::DeviceState state{};
    state.header.source_id.assign("thimble");
    state.joint_count = 3;
    idl::DeviceState received;
    bool got = false;
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    for (std::uint64_t seq = 1; !got && std::chrono::steady_clock::now() < deadline; ++seq) {
        state.header.seq = seq;
        link_.storeDeviceState(1, state);
        got = state_reader_.waitAndTake(received, 10ms);
    }
    ASSERT_TRUE(got) << "no DeviceState on DDS within 10 s";
    EXPECT_EQ(received.header().source_id(), "thimble");
    // The link counts a write after DDS returns, which may be after the reader took it.
    for (int i = 0; i < 1000 && link_.statesPublished() == 0; ++i) {
        std::this_thread::sleep_for(1ms);
    }
    EXPECT_GT(link_.statesPublished(), 0U);
}

TEST(SeqLockTryLoad, FailsBeforeTheFirstStoreAndReturnsTheVersionAfter) {
    daemon::SeqLock<std::array<std::uint64_t, 32>> slot;
    std::array<std::uint64_t, 32> out{};
    EXPECT_EQ(slot.tryLoad(out), 0U);
    std::array<std::uint64_t, 32> value{};
    value.fill(5);
    slot.store(value);
    slot.store(value);
    EXPECT_EQ(slot.tryLoad(out), 2U);
    EXPECT_EQ(out, value);
}

TEST(SeqLockTryLoad, NeverReportsATornCopyAsValid) {
    daemon::SeqLock<std::array<std::uint64_t, 64>> slot;
    std::atomic<std::uint64_t> valid{0};
    std::atomic<bool> done{false};
    // The writer keeps storing until the reader has checked enough copies (or 10 s pass, which
    // only a tryLoad that never succeeds would need), so the test never passes vacuously.
    std::thread writer([&] {
        std::array<std::uint64_t, 64> value{};
        const auto deadline = std::chrono::steady_clock::now() + 10s;
        for (std::uint64_t i = 1;
             valid.load() < 2000 && std::chrono::steady_clock::now() < deadline; ++i) {
            value.fill(i);
            slot.store(value);
            // Back-to-back stores leave a slow (sanitized) reader almost no window to finish a
            // copy: under ASan on 2 cores it took 9-10 s to see 2000. A pause now and then
            // gives it some; the stores still overlap its reads.
            if (i % 4 == 0) {
                std::this_thread::yield();
            }
        }
        done = true;
    });
    while (!done) {
        std::array<std::uint64_t, 64> out{};
        if (slot.tryLoad(out) != 0) {
            for (auto word : out) {
                ASSERT_EQ(word, out[0]) << "torn copy reported as valid";
            }
            valid.fetch_add(1);
        }
    }
    writer.join();
    EXPECT_GE(valid.load(), 2000U);
}

}  // namespace
}  // namespace haptic::hapticd
