// DDS Security on the sim link (#19): the PKI and signed permissions that
// scripts/dds-security-pki.sh makes, loaded by real Fast DDS participants through the
// profiles file it writes (the builtin PKI-DH, Access-Permissions and AES-GCM-GMAC plugins).
// The daemon's identity hears the sim's identity; a participant without a certificate of the
// lab's CA cannot drive the sim link, and an identity may write only what its grant allows.

#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include "ConstraintSetPubSubTypes.h"
#include "HapticCommandPubSubTypes.h"
#include "HapticStatusPubSubTypes.h"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/ipc/ipc_error.hpp"
#include "haptic/ipc/topics.hpp"

namespace haptic::testing {
namespace {

using namespace std::chrono_literals;

std::uint32_t testDomain() {
    // A domain of this test's own: the other DDS tests use 1-199.
    return 200 + static_cast<std::uint32_t>(::getpid() % 30);
}

class DdsSecurity : public ::testing::Test {
  protected:
    static void SetUpTestSuite() {
        char pattern[] = "/tmp/haptic-dds-pki.XXXXXX";
        ASSERT_NE(::mkdtemp(pattern), nullptr);
        pki_dir_ = pattern;
        const std::string command = std::string(HAPTIC_SOURCE_DIR) +
                                    "/scripts/dds-security-pki.sh " + pki_dir_ + " > " + pki_dir_ +
                                    "/pki.log 2>&1";
        ASSERT_EQ(std::system(command.c_str()), 0) << "see " << pki_dir_ << "/pki.log";
    }
    static void TearDownTestSuite() { std::filesystem::remove_all(pki_dir_); }

    static ipc::DdsSettings secure(const std::string& identity) {
        ipc::DdsSettings settings;
        settings.domain_id = testDomain();
        settings.profiles_file = pki_dir_ + "/" + identity + "_profiles.xml";
        settings.participant_profile = identity + "_secure";
        return settings;
    }
    static ipc::DdsSettings unauthenticated() {
        ipc::DdsSettings settings;
        settings.domain_id = testDomain();
        settings.profiles_file = std::string(HAPTIC_CONFIG_DIR) + "/dds_profiles.xml";
        settings.participant_profile = "haptic_participant";
        return settings;
    }

    // Writes `writer` every 50 ms until `reader` takes a sample or `timeout` passes.
    template <typename Writer, typename Reader>
    static bool delivered(Writer& writer, Reader& reader, std::chrono::milliseconds timeout) {
        idl::ConstraintSet sent;
        idl::ConstraintSet received;
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        while (std::chrono::steady_clock::now() < deadline) {
            writer.write(sent);
            if (reader.waitAndTake(received, 50ms)) {
                return true;
            }
        }
        return false;
    }

    static const std::string topic() { return ipc::deviceTopic(ipc::kConstraintSetTopic, "exo"); }

    static inline std::string pki_dir_;
};

TEST_F(DdsSecurity, TheSimIdentityDrivesTheDaemonIdentity) {
    ipc::DdsParticipant daemon(secure("hapticd"), "hapticd");
    ipc::DdsParticipant sim(secure("handsim"), "handsim");
    auto reader =
        daemon.createReader<idl::ConstraintSetPubSubType>(topic(), ipc::TopicKind::kLatestState);
    auto writer =
        sim.createWriter<idl::ConstraintSetPubSubType>(topic(), ipc::TopicKind::kLatestState);
    EXPECT_TRUE(delivered(writer, reader, 20s))
        << "authenticated participants with matching grants must match";
}

TEST_F(DdsSecurity, AParticipantWithoutTheLabsCertificateCannotDriveTheSimLink) {
    ipc::DdsParticipant daemon(secure("hapticd"), "hapticd");
    auto reader =
        daemon.createReader<idl::ConstraintSetPubSubType>(topic(), ipc::TopicKind::kLatestState);
    // The shipped profile, as any process on the host or the LAN would use it.
    ipc::DdsParticipant intruder(unauthenticated(), "intruder");
    auto writer =
        intruder.createWriter<idl::ConstraintSetPubSubType>(topic(), ipc::TopicKind::kLatestState);
    EXPECT_FALSE(delivered(writer, reader, 5s));
    EXPECT_EQ(writer.matchedReaders(), 0);

    // The secured side still works meanwhile: the refusal is the intruder's, not a dead link.
    ipc::DdsParticipant sim(secure("handsim"), "handsim");
    auto sim_writer =
        sim.createWriter<idl::ConstraintSetPubSubType>(topic(), ipc::TopicKind::kLatestState);
    EXPECT_TRUE(delivered(sim_writer, reader, 20s));
}

TEST_F(DdsSecurity, AnIdentityWritesOnlyWhatItsGrantAllows) {
    ipc::DdsParticipant operator_side(secure("operator"), "operator");
    // The operator's grant publishes haptic/command only: a writer on the sim link is refused
    // by the access-control plugin before anything is sent.
    EXPECT_THROW(operator_side.createWriter<idl::ConstraintSetPubSubType>(
                     topic(), ipc::TopicKind::kLatestState),
                 ipc::IpcError);
    EXPECT_NO_THROW(operator_side.createWriter<idl::HapticCommandPubSubType>(
        ipc::kCommandTopic, ipc::TopicKind::kStream));
    // And the sim may not command the daemon.
    ipc::DdsParticipant sim(secure("handsim"), "handsim");
    EXPECT_THROW(
        sim.createWriter<idl::HapticCommandPubSubType>(ipc::kCommandTopic, ipc::TopicKind::kStream),
        ipc::IpcError);
    // Only hapticd may write haptic/status.
    EXPECT_THROW(sim.createWriter<idl::HapticStatusPubSubType>(ipc::kStatusTopic,
                                                               ipc::TopicKind::kLatestState),
                 ipc::IpcError);
    EXPECT_THROW(operator_side.createWriter<idl::HapticStatusPubSubType>(
                     ipc::kStatusTopic, ipc::TopicKind::kLatestState),
                 ipc::IpcError);
    ipc::DdsParticipant daemon(secure("hapticd"), "hapticd");
    EXPECT_NO_THROW(daemon.createWriter<idl::HapticStatusPubSubType>(ipc::kStatusTopic,
                                                                     ipc::TopicKind::kLatestState));
}

}  // namespace
}  // namespace haptic::testing
