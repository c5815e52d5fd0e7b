#include "command_relay.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "haptic/ipc/topics.hpp"
#include "haptic/msgs/conversions.hpp"
#include "haptic/msgs/names.hpp"

namespace haptic::hapticd {
namespace {
constexpr std::size_t kRecordedReplies = 32;

}  // namespace

CommandRelay::CommandRelay(ipc::DdsParticipant& participant, daemon::CommandChannel& channel,
                           control::ControlServer& local)
    : channel_(channel),
      local_(local),
      commands_(participant.createReader<idl::HapticCommandPubSubType>(ipc::kCommandTopic,
                                                                       ipc::TopicKind::kStream)),
      replies_(participant.createWriter<idl::HapticCommandReplyPubSubType>(
          ipc::kCommandReplyTopic, ipc::TopicKind::kStream)) {}

const msgs::HapticCommandReply* CommandRelay::recorded(std::uint64_t request_id) const {
    const auto it = std::find_if(recent_.begin(), recent_.end(),
                                 [&](const auto& reply) { return reply.request_id == request_id; });
    return it == recent_.end() ? nullptr : &*it;
}

void CommandRelay::reply(const msgs::HapticCommandReply& reply) {
    replies_.write(msgs::toIdl(reply));
    recent_.push_back(reply);
    if (recent_.size() > kRecordedReplies) {
        recent_.pop_front();
    }
}

void CommandRelay::refuse(std::uint64_t request_id, const std::string& reason) {
    msgs::HapticCommandReply refusal;
    refusal.header.seq = ++reply_seq_;
    refusal.header.source_id.assign("hapticd");
    refusal.request_id = request_id;
    refusal.accepted = false;
    refusal.message.assign(reason);
    reply(refusal);
}

void CommandRelay::poll() {
    idl::HapticCommand sample;
    while (commands_.take(sample)) {
        msgs::HapticCommand command;
        if (const auto result = msgs::fromIdl(sample, command); !result.ok()) {
            spdlog::warn("command {} rejected: {}", sample.request_id(), result.error);
            refuse(sample.request_id(), "malformed command: " + result.error);
            continue;
        }
        if (const auto* answer = recorded(command.request_id); answer != nullptr) {
            replies_.write(msgs::toIdl(*answer));
            continue;
        }
        if (std::find(in_flight_.begin(), in_flight_.end(), command.request_id) !=
            in_flight_.end()) {
            continue;  // a resend of a command the RT thread has not answered yet
        }
        if (command.kind != msgs::CommandKind::kEstop) {
            spdlog::warn("command {} '{}' over DDS refused: only estop is taken over DDS",
                         command.request_id, msgs::toString(command.kind));
            refuse(command.request_id,
                   "over DDS only estop is taken (DDS carries no identity); operate with "
                   "hapticctl on hapticd's host, through its local control socket");
            continue;
        }
        if (!channel_.submit(command)) {
            refuse(command.request_id, "the RT loop is not taking commands (queue full)");
            continue;
        }
        in_flight_.push_back(command.request_id);
        spdlog::info("command {} '{}' {}", command.request_id, msgs::toString(command.kind),
                     command.argument.view());
    }
    msgs::HapticCommandReply answer;
    while (channel_.takeReply(answer)) {
        if (local_.deliver(answer)) {
            continue;  // a local caller's, answered on the socket
        }
        in_flight_.erase(std::remove(in_flight_.begin(), in_flight_.end(), answer.request_id),
                         in_flight_.end());
        spdlog::info("command {} {}: {}", answer.request_id,
                     answer.accepted ? "accepted" : "refused", answer.message.view());
        reply(answer);
    }
}

}  // namespace haptic::hapticd
