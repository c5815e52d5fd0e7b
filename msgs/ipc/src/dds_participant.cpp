#include "haptic/ipc/dds_participant.hpp"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <filesystem>

namespace haptic::ipc {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

DdsParticipant::DdsParticipant(const DdsSettings& settings, const std::string& name)
    : settings_(settings) {
    auto* factory = dds::DomainParticipantFactory::get_instance();
    if (!settings.profiles_file.empty()) {
        if (!std::filesystem::exists(settings.profiles_file)) {
            throw IpcError("DDS profiles file not found: " + settings.profiles_file);
        }
        if (factory->load_XML_profiles_file(settings.profiles_file) != ReturnCode_t::RETCODE_OK) {
            throw IpcError("DDS profiles file " + settings.profiles_file +
                           " could not be loaded (malformed XML or schema error; Fast DDS logs "
                           "the line above)");
        }
        dds::DomainParticipantQos qos;
        if (factory->get_participant_qos_from_profile(settings.participant_profile, qos) !=
            ReturnCode_t::RETCODE_OK) {
            throw IpcError("DDS profiles file " + settings.profiles_file +
                           " has no participant profile '" + settings.participant_profile + "'");
        }
        qos.name(name);
        participant_ = factory->create_participant(settings.domain_id, qos);
    } else {
        dds::DomainParticipantQos qos = dds::PARTICIPANT_QOS_DEFAULT;
        qos.name(name);
        participant_ = factory->create_participant(settings.domain_id, qos);
    }
    if (participant_ == nullptr) {
        throw IpcError("could not create the DDS participant on domain " +
                       std::to_string(settings.domain_id) + " (profile '" +
                       settings.participant_profile + "')");
    }
    publisher_ = participant_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
    subscriber_ = participant_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
    if (publisher_ == nullptr || subscriber_ == nullptr) {
        throw IpcError("could not create the DDS publisher/subscriber");
    }
}

DdsParticipant::~DdsParticipant() {
    if (participant_ != nullptr) {
        participant_->delete_contained_entities();
        dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
    }
}

std::string DdsParticipant::registerType(dds::TopicDataType* type) {
    dds::TypeSupport support(type);
    const std::string name = support.get_type_name();
    // Registering a name twice is harmless; DDS keeps the first registration.
    if (participant_->find_type(name).empty()) {
        support.register_type(participant_);
    }
    return name;
}

dds::Topic* DdsParticipant::topicFor(const std::string& topic, const std::string& type_name) {
    if (auto* existing = participant_->find_topic(topic, eprosima::fastrtps::Duration_t(0, 0))) {
        return existing;
    }
    dds::Topic* created = participant_->create_topic(topic, type_name, dds::TOPIC_QOS_DEFAULT);
    if (created == nullptr) {
        throw IpcError("could not create DDS topic '" + topic + "' of type " + type_name);
    }
    return created;
}

dds::DataWriter* DdsParticipant::createRawWriter(const std::string& topic,
                                                 const std::string& type_name, TopicKind kind) {
    dds::DataWriterQos qos = dds::DATAWRITER_QOS_DEFAULT;
    qos.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    qos.durability().kind = dds::VOLATILE_DURABILITY_QOS;
    qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    qos.history().depth = kind == TopicKind::kLatestState ? 1 : 64;
    qos.data_sharing().off();
    auto* writer = publisher_->create_datawriter(topicFor(topic, type_name), qos);
    if (writer == nullptr) {
        throw IpcError("could not create a DDS writer for '" + topic + "'");
    }
    return writer;
}

dds::DataReader* DdsParticipant::createRawReader(const std::string& topic,
                                                 const std::string& type_name, TopicKind kind) {
    dds::DataReaderQos qos = dds::DATAREADER_QOS_DEFAULT;
    qos.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    qos.durability().kind = dds::VOLATILE_DURABILITY_QOS;
    qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    qos.history().depth = kind == TopicKind::kLatestState ? 1 : 64;
    qos.data_sharing().off();
    auto* reader = subscriber_->create_datareader(topicFor(topic, type_name), qos);
    if (reader == nullptr) {
        throw IpcError("could not create a DDS reader for '" + topic + "'");
    }
    return reader;
}

}  // namespace haptic::ipc
