#pragma once

// A thin RAII layer over the Fast DDS 2.9 DCPS API: one participant per process, created
// from the XML profile in config/, and typed writers/readers for the generated types.
// Non-RT threads only (DDS allocates and locks).

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <ctime>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <memory>
#include <string>

#include "haptic/config/common.hpp"
#include "haptic/ipc/ipc_error.hpp"

namespace haptic::ipc {

struct DdsSettings {
    std::uint32_t domain_id{0};
    std::string profiles_file;  // Fast DDS XML profiles; empty = built-in defaults
    std::string participant_profile{"haptic_participant"};
};

// The settings a configuration's `dds:` block names (daemon.yaml, sim.yaml, user.yaml).
[[nodiscard]] inline DdsSettings ddsSettings(const config::DdsConfig& dds) {
    return {static_cast<std::uint32_t>(dds.domain_id), dds.profiles_file.string(),
            dds.participant_profile};
}

// How a topic behaves. kLatestState: reliable, keep-last 1 (status, the sim link: only the
// newest value matters). kStream: reliable, keep-last 64 (telemetry, commands, replies: no
// sample may be dropped while the reader keeps up).
enum class TopicKind { kLatestState, kStream };

template <typename T>
class DdsWriter {
  public:
    DdsWriter() = default;
    explicit DdsWriter(eprosima::fastdds::dds::DataWriter* writer) : writer_(writer) {}
    // Returns false if DDS refused the sample (for example, the history is full).
    bool write(const T& sample) {
        return writer_ != nullptr && writer_->write(const_cast<T*>(&sample));
    }
    [[nodiscard]] int matchedReaders() const;

  private:
    eprosima::fastdds::dds::DataWriter* writer_{nullptr};
};

template <typename T>
class DdsReader {
  public:
    DdsReader() = default;
    explicit DdsReader(eprosima::fastdds::dds::DataReader* reader) : reader_(reader) {}
    // Takes the next unread sample; false when none is waiting.
    bool take(T& sample) {
        eprosima::fastdds::dds::SampleInfo info;
        while (reader_ != nullptr && reader_->take_next_sample(&sample, &info) == ReturnOk()) {
            if (info.valid_data) {
                return true;
            }
        }
        return false;
    }
    // The same, with when this reader received it, on CLOCK_MONOTONIC (for latencies).
    // Fast DDS stamps the reception with the system clock; it is carried over to the monotonic
    // clock through both clocks' readings now, so a wall-clock step between reception and
    // take would show in it (never negative: clamped to now).
    bool take(T& sample, std::int64_t& received_monotonic_ns) {
        eprosima::fastdds::dds::SampleInfo info;
        while (reader_ != nullptr && reader_->take_next_sample(&sample, &info) == ReturnOk()) {
            if (info.valid_data) {
                timespec realtime{};
                timespec monotonic{};
                ::clock_gettime(CLOCK_REALTIME, &realtime);
                ::clock_gettime(CLOCK_MONOTONIC, &monotonic);
                const auto ns = [](const timespec& ts) {
                    return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
                };
                const std::int64_t received_ns = info.reception_timestamp.to_ns();
                // Without a reception stamp (none, or from a clock far off) it counts as now.
                const std::int64_t waited_ns =
                    received_ns > 0 && ns(realtime) - received_ns < 10'000'000'000
                        ? std::max<std::int64_t>(0, ns(realtime) - received_ns)
                        : 0;
                received_monotonic_ns = ns(monotonic) - waited_ns;
                return true;
            }
        }
        return false;
    }
    // Blocks up to `timeout` for a sample; false on timeout.
    bool waitAndTake(T& sample, std::chrono::milliseconds timeout) {
        if (take(sample)) {
            return true;
        }
        const auto seconds = static_cast<std::int32_t>(timeout.count() / 1000);
        const auto nanos = static_cast<std::uint32_t>((timeout.count() % 1000) * 1000000);
        if (reader_ == nullptr ||
            !reader_->wait_for_unread_message(eprosima::fastrtps::Duration_t(seconds, nanos))) {
            return false;
        }
        return take(sample);
    }
    // For waiting on several readers at once (a DDS WaitSet on each reader's StatusCondition).
    [[nodiscard]] eprosima::fastdds::dds::DataReader* handle() const noexcept { return reader_; }

  private:
    static eprosima::fastrtps::types::ReturnCode_t ReturnOk() {
        return eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
    }
    eprosima::fastdds::dds::DataReader* reader_{nullptr};
};

class DdsParticipant {
  public:
    // Throws IpcError naming the profiles file or profile when the participant cannot be
    // created (a malformed XML file, an unknown profile name).
    DdsParticipant(const DdsSettings& settings, const std::string& name);
    ~DdsParticipant();
    DdsParticipant(const DdsParticipant&) = delete;
    DdsParticipant& operator=(const DdsParticipant&) = delete;

    // PubSubType is a type generated by fastddsgen (for example idl::HapticStatusPubSubType).
    template <typename PubSubType>
    DdsWriter<typename PubSubType::type> createWriter(const std::string& topic, TopicKind kind) {
        return DdsWriter<typename PubSubType::type>(
            createRawWriter(topic, registerType(new PubSubType()), kind));
    }
    template <typename PubSubType>
    DdsReader<typename PubSubType::type> createReader(const std::string& topic, TopicKind kind) {
        return DdsReader<typename PubSubType::type>(
            createRawReader(topic, registerType(new PubSubType()), kind));
    }

    [[nodiscard]] const DdsSettings& settings() const noexcept { return settings_; }

  private:
    std::string registerType(eprosima::fastdds::dds::TopicDataType* type);
    eprosima::fastdds::dds::Topic* topicFor(const std::string& topic, const std::string& type_name);
    eprosima::fastdds::dds::DataWriter* createRawWriter(const std::string& topic,
                                                        const std::string& type_name,
                                                        TopicKind kind);
    eprosima::fastdds::dds::DataReader* createRawReader(const std::string& topic,
                                                        const std::string& type_name,
                                                        TopicKind kind);

    DdsSettings settings_;
    eprosima::fastdds::dds::DomainParticipant* participant_{nullptr};
    eprosima::fastdds::dds::Publisher* publisher_{nullptr};
    eprosima::fastdds::dds::Subscriber* subscriber_{nullptr};
};

template <typename T>
int DdsWriter<T>::matchedReaders() const {
    if (writer_ == nullptr) {
        return 0;
    }
    eprosima::fastdds::dds::PublicationMatchedStatus status;
    writer_->get_publication_matched_status(status);
    return status.current_count;
}

}  // namespace haptic::ipc
