#include "haptic/protocol/frame_codec.hpp"

namespace haptic::protocol {
namespace {

// CRC-8/SAE-J1850: poly 0x1D, init 0xFF, final xor 0xFF (check value 0x4B for "123456789").
constexpr std::array<std::uint8_t, 256> makeCrcTable() noexcept {
    std::array<std::uint8_t, 256> table{};
    for (int byte = 0; byte < 256; ++byte) {
        std::uint8_t crc = static_cast<std::uint8_t>(byte);
        for (int bit = 0; bit < 8; ++bit) {
            crc = static_cast<std::uint8_t>((crc & 0x80) != 0 ? (crc << 1) ^ 0x1D : crc << 1);
        }
        table[static_cast<std::size_t>(byte)] = crc;
    }
    return table;
}
constexpr std::array<std::uint8_t, 256> kCrcTable = makeCrcTable();

}  // namespace

const char* toString(RejectReason reason) noexcept {
    switch (reason) {
        case RejectReason::kWrongLength:
            return "wrong length";
        case RejectReason::kWrongFrameType:
            return "wrong frame type";
        case RejectReason::kBadCrc:
            return "bad CRC";
        case RejectReason::kUnknownKind:
            return "unknown kind";
        case RejectReason::kRepeatedCounter:
            return "repeated counter";
        case RejectReason::kCounterJump:
            return "counter jump";
        case RejectReason::kOutOfRange:
            return "out of range";
        case RejectReason::kReservedNotZero:
            return "reserved not zero";
        case RejectReason::kCount:
            break;
    }
    return "unknown";
}

std::uint64_t RejectCounters::total() const noexcept {
    std::uint64_t sum = 0;
    for (std::uint64_t count : by_reason) {
        sum += count;
    }
    return sum;
}

std::uint8_t crc8SaeJ1850(std::uint32_t id, const std::uint8_t* bytes_1_to_7) noexcept {
    std::uint8_t crc = 0xFF;
    crc = kCrcTable[crc ^ static_cast<std::uint8_t>(id & 0xFF)];
    crc = kCrcTable[crc ^ static_cast<std::uint8_t>((id >> 8) & 0xFF)];
    for (int i = 0; i < 7; ++i) {
        crc = kCrcTable[crc ^ bytes_1_to_7[i]];
    }
    return static_cast<std::uint8_t>(crc ^ 0xFF);
}

SequenceChecker::Result SequenceChecker::check(std::uint8_t counter) noexcept {
    counter &= 0x0F;
    if (!synced_) {
        synced_ = true;
        last_ = counter;
        return Result::kInOrder;
    }
    const auto gap = static_cast<std::uint8_t>((counter - last_) & 0x0F);
    if (gap == 0) {
        return Result::kRepeated;
    }
    last_ = counter;
    if (gap > kMaxCounterGap) {
        return Result::kJump;
    }
    lost_ += gap - 1U;
    return Result::kInOrder;
}

void sealFrame(can::CanFrame& frame, std::uint8_t kind, std::uint8_t counter) noexcept {
    frame.length = kFrameLength;
    frame.flags = 0;
    frame.data[1] = static_cast<std::uint8_t>((kind << 4) | (counter & 0x0F));
    frame.data[0] = crc8SaeJ1850(frame.id, &frame.data[1]);
}

bool checkFrame(const can::CanFrame& frame, RejectReason& reason) noexcept {
    if ((frame.flags &
         (can::kFlagFd | can::kFlagRemote | can::kFlagExtendedId | can::kFlagError)) != 0) {
        reason = RejectReason::kWrongFrameType;
        return false;
    }
    if (frame.length != kFrameLength) {
        reason = RejectReason::kWrongLength;
        return false;
    }
    if (crc8SaeJ1850(frame.id, &frame.data[1]) != frame.data[0]) {
        reason = RejectReason::kBadCrc;
        return false;
    }
    return true;
}

void encodeHeartbeat(std::uint32_t id, const Heartbeat& heartbeat, std::uint8_t counter,
                     can::CanFrame& frame) noexcept {
    frame = blankFrame(id);
    frame.data[2] = static_cast<std::uint8_t>(heartbeat.mode);
    frame.data[3] = heartbeat.active_fault;
    putU32(frame, 4, heartbeat.uptime_ms);
    sealFrame(frame, 0, counter);
}

void encodeFault(std::uint32_t id, const FaultReport& fault, std::uint8_t counter,
                 can::CanFrame& frame) noexcept {
    frame = blankFrame(id);
    frame.data[2] = static_cast<std::uint8_t>(fault.code);
    frame.data[3] = fault.active ? 1 : 0;
    putU32(frame, 4, fault.detail);
    sealFrame(frame, 0, counter);
}

bool decodeHeartbeatPayload(const can::CanFrame& frame, Heartbeat& out,
                            RejectReason& reason) noexcept {
    if (frameKind(frame) != 0) {
        reason = RejectReason::kUnknownKind;
        return false;
    }
    if (frame.data[2] > static_cast<std::uint8_t>(DeviceMode::kFault) ||
        frame.data[3] > kMaxDeviceFaultCode) {
        reason = RejectReason::kOutOfRange;
        return false;
    }
    out.mode = static_cast<DeviceMode>(frame.data[2]);
    out.active_fault = frame.data[3];
    out.uptime_ms = getU32(frame, 4);
    return true;
}

bool decodeFaultPayload(const can::CanFrame& frame, FaultReport& out,
                        RejectReason& reason) noexcept {
    if (frameKind(frame) != 0) {
        reason = RejectReason::kUnknownKind;
        return false;
    }
    if (frame.data[2] == 0 || frame.data[2] > kMaxDeviceFaultCode) {
        reason = RejectReason::kOutOfRange;
        return false;
    }
    if (frame.data[3] > 1) {
        reason = RejectReason::kReservedNotZero;
        return false;
    }
    out.code = static_cast<DeviceFaultCode>(frame.data[2]);
    out.active = frame.data[3] == 1;
    out.detail = getU32(frame, 4);
    return true;
}

}  // namespace haptic::protocol
