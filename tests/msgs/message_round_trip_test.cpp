// Every field of every message survives twin -> DDS type -> CDR bytes -> DDS type -> twin.
// Each twin is filled to capacity with distinct pseudo-random values, so a field that one
// side forgets, a capacity that differs from the IDL bound or a swapped pair of fields all
// fail here; the measuring walk below catches a field that exists on one side only.

#include <fastdds/rtps/common/SerializedPayload.h>
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <type_traits>

#include "ConstraintSetPubSubTypes.h"
#include "ContactSurfacePubSubTypes.h"
#include "DeviceStatePubSubTypes.h"
#include "HandPosePubSubTypes.h"
#include "HapticCommandPubSubTypes.h"
#include "HapticStatusPubSubTypes.h"
#include "HapticTelemetryPubSubTypes.h"
#include "SimStatusPubSubTypes.h"
#include "haptic/msgs/conversions.hpp"

namespace haptic::msgs {
namespace {

// Walks every field of a twin in IDL order. In kFill mode it writes distinct values; in
// kMeasure mode it adds up the maximum CDR size the walk implies (XCDR1 alignment), which
// must equal the generated type's getMaxCdrSerializedSize(): a field present in one schema
// and not the other, or in a different order, changes one side. Overloads exist for every
// field type the twins use, so a new field type fails to compile here.
class Filler {
  public:
    enum class Mode { kFill, kMeasure };
    explicit Filler(std::uint32_t seed, Mode mode = Mode::kFill) : rng_(seed), mode_(mode) {}

    [[nodiscard]] std::size_t measuredSize() const { return size_; }

    void fill(double& v) {
        if (measure(8))
            return;
        v = std::uniform_real_distribution<double>(-1e3, 1e3)(rng_);
    }
    void fill(bool& v) {
        if (measure(1))
            return;
        v = (rng_() & 1U) != 0;
    }
    void fill(std::uint8_t& v) {
        if (measure(1))
            return;
        v = static_cast<std::uint8_t>(rng_());
    }
    void fill(std::uint16_t& v) {
        if (measure(2))
            return;
        v = static_cast<std::uint16_t>(rng_());
    }
    void fill(std::int16_t& v) {
        if (measure(2))
            return;
        v = static_cast<std::int16_t>(rng_());
    }
    void fill(std::uint32_t& v) {
        if (measure(4))
            return;
        v = static_cast<std::uint32_t>(rng_());
    }
    void fill(std::uint64_t& v) {
        if (measure(8))
            return;
        v = (static_cast<std::uint64_t>(rng_()) << 32U) | rng_();
    }
    void fill(std::int64_t& v) {
        if (measure(8))
            return;
        v = static_cast<std::int64_t>((static_cast<std::uint64_t>(rng_()) << 32U) | rng_());
    }
    template <typename E>
    requires std::is_enum_v<E>
    void fill(E& v, E last) {
        if (measure(4))
            return;
        v = static_cast<E>(rng_() % (static_cast<std::uint32_t>(last) + 1));
    }
    template <std::size_t N>
    void fill(FixedString<N>& s) {
        if (mode_ == Mode::kMeasure) {
            measure(4);  // length
            size_ += N;  // N - 1 characters and the NUL
            return;
        }
        // Full length, printable, so truncation at either side shows.
        std::string text(N - 1, 'x');
        for (auto& c : text) {
            c = static_cast<char>('a' + rng_() % 26);
        }
        s.assign(text);
    }
    template <typename T, std::size_t N>
    void fill(std::array<T, N>& values) {
        for (auto& v : values) {
            fill(v);
        }
    }
    template <typename T, std::size_t N>
    void fill(BoundedArray<T, N>& list) {
        if (mode_ == Mode::kMeasure) {
            measure(4);  // sequence length
        }
        list.clear();
        for (std::size_t i = 0; i < N; ++i) {
            T item{};
            fill(item);
            list.push_back(item);
        }
    }

    void fill(MessageHeader& h) {
        // The schema stays this build's, or the reader refuses the message.
        (void)measure(4);
        h.schema = kSchema;
        fill(h.seq);
        fill(h.stamp_ns);
        fill(h.source_id);
    }
    void fill(TrackingOrigin& o) {
        fill(o.sampled_ns);
        fill(o.received_ns);
    }
    void fill(Percentiles& p) {
        fill(p.p50);
        fill(p.p99);
        fill(p.max);
    }
    void fill(ContactKinematics& k) {
        fill(k.joints);
        fill(k.gap_m);
        fill(k.normal);
        fill(k.q_ref_rad);
        fill(k.axis);
        fill(k.lever_m);
    }
    void fill(LinearConstraint& c) {
        fill(c.a);
        fill(c.b);
        fill(c.contact);
    }
    void fill(ConstraintSet& m) {
        fill(m.header);
        fill(m.dof);
        fill(m.q_sim_rad);
        fill(m.constraints);
        fill(m.reference_torque_nm);
        fill(m.tracking);
    }
    void fill(ContactSample& s) {
        fill(s.p_device_m);
        fill(s.signed_distance_m);
        fill(s.normal_device);
        fill(s.weight);
    }
    void fill(ContactSurface& m) {
        fill(m.header);
        fill(m.samples);
        fill(m.reference_force_device_n);
        fill(m.reference_moment_device_nm);
        fill(m.tracking);
    }
    void fill(DeviceState& m) {
        fill(m.header);
        fill(m.joint_count);
        fill(m.joint_position_rad);
        fill(m.joint_velocity_rad_per_s);
        fill(m.actuator_count);
        fill(m.actuator_position);
        fill(m.actuator_force);
        fill(m.platform_position_m);
        fill(m.platform_orientation_wxyz);
        fill(m.status_bits);
    }
    void fill(HandPose& m) {
        fill(m.header);
        fill(m.wrist_position_m);
        fill(m.wrist_orientation_wxyz);
        fill(m.joint_angles_rad);
        fill(m.confidence);
    }
    void fill(LoopStatistics& l) {
        fill(l.rate_hz);
        fill(l.ticks);
        fill(l.overruns);
        fill(l.overruns_read);
        fill(l.overruns_compute);
        fill(l.overruns_write);
        fill(l.period_us);
        fill(l.wakeup_latency_us);
        fill(l.tick_work_us);
    }
    void fill(DeviceStatus& d) {
        fill(d.device_id);
        fill(d.kind, DeviceKind::kThimble);
        fill(d.state, DeviceRunState::kFault);
        fill(d.can.bus_state, BusState::kBusOff);
        fill(d.can.rx_frames);
        fill(d.can.tx_frames);
        fill(d.can.rx_errors);
        fill(d.can.tx_errors);
        fill(d.can.rejected_frames);
        fill(d.last_frame_age_ms);
        fill(d.awaiting_enable);
    }
    void fill(Fault& f) {
        fill(f.code);
        fill(f.device_id);
        fill(f.message);
    }
    void fill(HapticStatus& m) {
        fill(m.header);
        fill(m.state, DaemonState::kEstop);
        fill(m.rendering_method);
        fill(m.uptime_s);
        fill(m.loop);
        fill(m.devices);
        fill(m.sim_link.transport, SimTransport::kDds);
        fill(m.sim_link.connected);
        fill(m.sim_link.age_ms);
        fill(m.sim_link.rate_hz);
        fill(m.sim_link.received);
        fill(m.sim_link.rejected);
        fill(m.sim_link.rejected_by_reason);
        fill(m.sim_link.late_input_ticks);
        fill(m.faults);
        fill(m.version);
        fill(m.config_digest);
    }
    void fill(TelemetrySample& s) {
        fill(s.tick);
        fill(s.stamp_ns);
        fill(s.device_index);
        fill(s.device_kind, DeviceKind::kThimble);
        fill(s.exoskeleton.actuator_force_cmd_n);
        fill(s.exoskeleton.actuator_force_n);
        fill(s.exoskeleton.joint_position_rad);
        fill(s.exoskeleton.proxy_position_rad);
        fill(s.exoskeleton.reference_torque_nm);
        fill(s.exoskeleton.reference_actuator_force_n);
        fill(s.exoskeleton.ghost_torque_nm);
        fill(s.exoskeleton.energy_observer_j);
        fill(s.exoskeleton.environment_work_j);
        fill(s.thimble.servo_angle_cmd_rad);
        fill(s.thimble.servo_angle_rad);
        fill(s.thimble.platform_height_m);
        fill(s.thimble.platform_tilt_x_rad);
        fill(s.thimble.platform_tilt_y_rad);
        fill(s.thimble.reference_force_device_n);
        fill(s.thimble.reference_moment_device_nm);
        fill(s.thimble.pad_force_model_n);
        fill(s.thimble.pad_limit_flags);
        fill(s.tick_work_us);
        fill(s.read_us);
        fill(s.write_us);
        fill(s.wakeup_latency_us);
        fill(s.tracking);
    }
    void fill(HapticTelemetry& m) {
        fill(m.header);
        fill(m.samples);
    }
    void fill(HapticCommand& m) {
        fill(m.header);
        fill(m.request_id);
        fill(m.kind, CommandKind::kClearFault);
        fill(m.device_id);
        fill(m.argument);
    }
    void fill(HapticCommandReply& m) {
        fill(m.header);
        fill(m.request_id);
        fill(m.accepted);
        fill(m.message);
    }
    void fill(SimStatus& m) {
        fill(m.header);
        fill(m.rate_hz);
        fill(m.steps);
        fill(m.step_time_us);
        fill(m.node_count);
        fill(m.element_count);
        fill(m.solver_residual);
        fill(m.solver_iterations);
        fill(m.energy_j);
        fill(m.model);
        fill(m.steps_zeroed);
        fill(m.steps_substepped);
        fill(m.inputs_rejected);
        fill(m.last_rejection);
        fill(m.steps_rescaled);
    }

  private:
    // In kMeasure mode: align to the primitive's size and add it; returns true so the caller
    // skips filling.
    bool measure(std::size_t bytes) {
        if (mode_ != Mode::kMeasure) {
            return false;
        }
        size_ += (bytes - size_ % bytes) % bytes;
        size_ += bytes;
        return true;
    }

    std::mt19937 rng_;
    Mode mode_;
    std::size_t size_{0};
};

template <typename Twin, typename PubSubType>
void expectRoundTrip(std::uint32_t seed) {
    Twin original{};
    Filler(seed).fill(original);
    // The filler touched every field: a twin default-constructed differs from it.
    ASSERT_FALSE(original == Twin{});

    Twin measured{};
    Filler sizer(seed, Filler::Mode::kMeasure);
    sizer.fill(measured);
    using Dds = typename PubSubType::type;
    EXPECT_EQ(sizer.measuredSize(), Dds::getMaxCdrSerializedSize())
        << "the twin's fields and the IDL's fields differ in number, type, bound or order";

    auto dds_out = toIdl(original);
    PubSubType type;
    eprosima::fastrtps::rtps::SerializedPayload_t payload(type.m_typeSize);
    ASSERT_TRUE(type.serialize(&dds_out, &payload))
        << "a twin filled to capacity must fit the IDL bounds";

    // Filled to capacity with strings at full length, the sample must be exactly as large as
    // the largest sample the IDL allows; a bound larger or smaller than the twin's capacity
    // changes one side of this equation.
    EXPECT_EQ(Dds::getCdrSerializedSize(dds_out), Dds::getMaxCdrSerializedSize())
        << "IDL bounds and twin capacities differ";

    Dds dds_in;
    ASSERT_TRUE(type.deserialize(&payload, &dds_in));
    EXPECT_EQ(dds_in, dds_out);

    Twin restored{};
    const ConversionResult result = fromIdl(dds_in, restored);
    ASSERT_TRUE(result.ok()) << result.error;
    EXPECT_TRUE(restored == original) << "a field was lost or changed on the way";
}

TEST(MessageRoundTrip, ConstraintSet) {
    expectRoundTrip<ConstraintSet, idl::ConstraintSetPubSubType>(1);
}
TEST(MessageRoundTrip, ContactSurface) {
    expectRoundTrip<ContactSurface, idl::ContactSurfacePubSubType>(2);
}
TEST(MessageRoundTrip, DeviceState) {
    expectRoundTrip<DeviceState, idl::DeviceStatePubSubType>(3);
}
TEST(MessageRoundTrip, HandPose) {
    expectRoundTrip<HandPose, idl::HandPosePubSubType>(4);
}
TEST(MessageRoundTrip, HapticStatus) {
    expectRoundTrip<HapticStatus, idl::HapticStatusPubSubType>(5);
}
TEST(MessageRoundTrip, HapticTelemetry) {
    expectRoundTrip<HapticTelemetry, idl::HapticTelemetryPubSubType>(6);
}
TEST(MessageRoundTrip, HapticCommand) {
    expectRoundTrip<HapticCommand, idl::HapticCommandPubSubType>(7);
}
TEST(MessageRoundTrip, HapticCommandReply) {
    expectRoundTrip<HapticCommandReply, idl::HapticCommandReplyPubSubType>(8);
}
TEST(MessageRoundTrip, SimStatus) {
    expectRoundTrip<SimStatus, idl::SimStatusPubSubType>(9);
}

TEST(MessageConversion, RejectsEnumOutsideItsRange) {
    idl::HapticStatus status = toIdl(HapticStatus{});
    status.state(static_cast<idl::DaemonState>(99));
    HapticStatus twin;
    const ConversionResult result = fromIdl(status, twin);
    EXPECT_FALSE(result.ok());
    EXPECT_NE(result.error.find("HapticStatus.state"), std::string::npos) << result.error;
}

TEST(MessageConversion, RejectsSequenceLongerThanCapacity) {
    idl::ContactSurface surface = toIdl(ContactSurface{});
    surface.samples().resize(kMaxContactSamples + 1);
    ContactSurface twin;
    const ConversionResult result = fromIdl(surface, twin);
    EXPECT_FALSE(result.ok());
    EXPECT_NE(result.error.find("ContactSurface.samples"), std::string::npos) << result.error;
}

}  // namespace
}  // namespace haptic::msgs
