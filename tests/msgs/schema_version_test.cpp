// msgs::kSchema (a mark and kSchemaVersion): every message carries it first, every conversion
// refuses another one, and this file records the layout the version stands for, so a layout
// change without a new version fails here rather than between two releases in a lab.

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <tuple>
#include <utility>

#include "ConstraintSetPubSubTypes.h"
#include "ContactSurfacePubSubTypes.h"
#include "DeviceStatePubSubTypes.h"
#include "HandPosePubSubTypes.h"
#include "HapticCommandPubSubTypes.h"
#include "HapticStatusPubSubTypes.h"
#include "HapticTelemetryPubSubTypes.h"
#include "SimStatusPubSubTypes.h"
#include "haptic/msgs/conversions.hpp"
#include "haptic/msgs/messages.hpp"

namespace haptic::msgs {
namespace {

// Each twin with its IDL type and the IDL type's Fast DDS support.
template <typename Twin, typename Idl, typename PubSub>
struct Kind {
    using twin = Twin;
    using idl_type = Idl;
    using pub_sub = PubSub;
    const char* name;
};
constexpr std::tuple kKinds{
    Kind<ConstraintSet, idl::ConstraintSet, idl::ConstraintSetPubSubType>{"ConstraintSet"},
    Kind<ContactSurface, idl::ContactSurface, idl::ContactSurfacePubSubType>{"ContactSurface"},
    Kind<DeviceState, idl::DeviceState, idl::DeviceStatePubSubType>{"DeviceState"},
    Kind<HandPose, idl::HandPose, idl::HandPosePubSubType>{"HandPose"},
    Kind<HapticStatus, idl::HapticStatus, idl::HapticStatusPubSubType>{"HapticStatus"},
    Kind<HapticTelemetry, idl::HapticTelemetry, idl::HapticTelemetryPubSubType>{"HapticTelemetry"},
    Kind<HapticCommand, idl::HapticCommand, idl::HapticCommandPubSubType>{"HapticCommand"},
    Kind<HapticCommandReply, idl::HapticCommandReply, idl::HapticCommandReplyPubSubType>{
        "HapticCommandReply"},
    Kind<SimStatus, idl::SimStatus, idl::SimStatusPubSubType>{"SimStatus"},
};

TEST(SchemaVersion, EveryMessageCarriesItAndEveryConversionRefusesAnother) {
    int kinds = 0;
    std::apply(
        [&](auto... kind) {
            (
                [&] {
                    using K = decltype(kind);
                    ++kinds;
                    typename K::twin sent{};
                    EXPECT_EQ(sent.header.schema, kSchema) << kind.name;
                    typename K::idl_type wire = toIdl(sent);
                    EXPECT_EQ(wire.header().schema(), kSchema) << kind.name;
                    typename K::twin received{};
                    received.header.schema = 0;
                    EXPECT_TRUE(fromIdl(wire, received).ok()) << kind.name;
                    EXPECT_EQ(received.header.schema, kSchema) << kind.name;

                    // A release before the field (its header began with seq: 1 reads as 1),
                    // the next version, and the mark alone.
                    for (const auto& [other, text] : {std::pair{std::uint32_t{1}, "0x00000001"},
                                                      std::pair{kSchema + 1, "0x48500002"},
                                                      std::pair{kSchemaMark, "0x48500000"}}) {
                        wire.header().schema(other);
                        wire.header().seq(77);
                        const ConversionResult result = fromIdl(wire, received);
                        EXPECT_EQ(result.error,
                                  std::string(kind.name) + ".header.schema: " + text +
                                      ", this build reads 0x48500001 (the sender is from another "
                                      "release; hapticd, handsim, hapticemu and hapticctl must "
                                      "come from one)");
                        EXPECT_EQ(received.header.schema, other) << "the header is read";
                        EXPECT_EQ(received.header.seq, 77U);
                    }
                }(),
                ...);
        },
        kKinds);
    EXPECT_EQ(kinds, static_cast<int>(std::tuple_size_v<decltype(kShmMessageTypes)>));
}

// FNV-1a over the header's members (offset and size of each: a member resized into padding
// leaves every size alone), and each message's twin size and alignment and its IDL type's
// largest CDR size.
std::uint64_t layoutFingerprint() {
    std::uint64_t hash = 14695981039346656037ULL;
    const auto mix = [&](std::uint64_t value) {
        for (int byte = 0; byte < 8; ++byte) {
            hash ^= (value >> (8 * byte)) & 0xFF;
            hash *= 1099511628211ULL;
        }
    };
    mix(offsetof(MessageHeader, schema));
    mix(sizeof(MessageHeader::schema));
    mix(offsetof(MessageHeader, seq));
    mix(offsetof(MessageHeader, stamp_ns));
    mix(offsetof(MessageHeader, source_id));
    mix(sizeof(MessageHeader::source_id));
    std::apply(
        [&](auto... kind) {
            (
                [&] {
                    using K = decltype(kind);
                    typename K::pub_sub support;
                    mix(sizeof(typename K::twin));
                    mix(alignof(typename K::twin));
                    mix(support.m_typeSize);
                }(),
                ...);
        },
        kKinds);
    return hash;
}

TEST(SchemaVersion, TheRecordedLayoutIsTheBuiltOne) {
    // What kSchemaVersion 1 stands for. A change to a message (a field added, removed or
    // resized, a capacity) changes this: then raise msgs::kSchemaVersion (messages.hpp) and
    // record both here. A reorder of fields of one size escapes it: raise the version then too.
    // The IDL's sizes are fastddsgen's: a fastddsgen that sizes the same IDL otherwise changes
    // it too (the wire then changed, and the version is raised all the same).
    constexpr std::uint16_t kRecordedVersion = 1;
    constexpr std::uint64_t kRecordedFingerprint = 0xcfb98ca6f7116084;
    EXPECT_EQ(kSchemaVersion, kRecordedVersion);
    EXPECT_EQ(layoutFingerprint(), kRecordedFingerprint)
        << "a message's layout changed: raise msgs::kSchemaVersion and record the new "
           "fingerprint 0x"
        << std::hex << layoutFingerprint();
}

}  // namespace
}  // namespace haptic::msgs
