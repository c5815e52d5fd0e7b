#include "haptic/can/udp_bus.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "haptic/can/clock.hpp"

namespace haptic::can {
namespace {

constexpr std::array<std::uint8_t, 4> kMagic{'H', 'C', 'A', 'N'};
constexpr std::uint8_t kKnownFlags =
    kFlagExtendedId | kFlagFd | kFlagBitRateSwitch | kFlagRemote | kFlagError;

sockaddr_in loopbackAddress(std::uint16_t port) noexcept {
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(port);
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    return address;
}

}  // namespace

std::string describe(const UdpBusConfig& config) {
    return "udp 127.0.0.1:" + std::to_string(config.base_port) + "+" + std::to_string(config.slots);
}

UdpBus::UdpBus(const UdpBusConfig& config) : config_(config) {
    if (config.slots < 2 || config.slots > kMaxSlots ||
        static_cast<std::uint32_t>(config.base_port) + config.slots > 65536U ||
        config.base_port == 0) {
        throw std::runtime_error("udp bus: slots must be 2-" + std::to_string(kMaxSlots) +
                                 " and the port block must fit below 65536");
    }
    state_.setPolicy(config.recovery);
    socket_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (socket_ < 0) {
        throw std::runtime_error(std::string("udp bus: socket: ") + std::strerror(errno));
    }
    for (std::uint16_t slot = 0; slot < config.slots; ++slot) {
        const sockaddr_in address = loopbackAddress(config.base_port + slot);
        if (::bind(socket_, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) == 0) {
            slot_ = slot;
            return;
        }
        if (errno != EADDRINUSE) {
            const int saved = errno;
            ::close(socket_);
            throw std::runtime_error(std::string("udp bus: bind: ") + std::strerror(saved));
        }
    }
    ::close(socket_);
    throw std::runtime_error("udp bus: all " + std::to_string(config.slots) + " ports of " +
                             describe(config) + " are taken");
}

UdpBus::~UdpBus() {
    if (socket_ >= 0) {
        ::close(socket_);
    }
}

std::size_t UdpBus::encode(const CanFrame& frame, std::uint8_t sender_slot, std::uint8_t* out,
                           std::size_t capacity) noexcept {
    const std::size_t size = kHeaderSize + frame.length;
    if (!isWellFormed(frame) || capacity < size) {
        return 0;
    }
    std::memcpy(out, kMagic.data(), kMagic.size());
    out[4] = kVersion;
    out[5] = frame.flags;
    out[6] = frame.length;
    out[7] = sender_slot;
    for (int i = 0; i < 4; ++i) {
        out[8 + i] = static_cast<std::uint8_t>(frame.id >> (8 * i));
    }
    std::memcpy(out + kHeaderSize, frame.data.data(), frame.length);
    return size;
}

bool UdpBus::decode(const std::uint8_t* datagram, std::size_t size, CanFrame& frame) noexcept {
    if (size < kHeaderSize || std::memcmp(datagram, kMagic.data(), kMagic.size()) != 0 ||
        datagram[4] != kVersion || (datagram[5] & ~kKnownFlags) != 0) {
        return false;
    }
    const std::uint8_t length = datagram[6];
    if (length > kFdMaxLength || size != kHeaderSize + length) {
        return false;
    }
    CanFrame decoded;
    decoded.flags = datagram[5];
    decoded.length = length;
    for (int i = 0; i < 4; ++i) {
        decoded.id |= static_cast<std::uint32_t>(datagram[8 + i]) << (8 * i);
    }
    std::memcpy(decoded.data.data(), datagram + kHeaderSize, length);
    if (!isWellFormed(decoded)) {
        return false;
    }
    frame = decoded;
    return true;
}

IoResult UdpBus::read(CanFrame& frame) noexcept {
    std::array<std::uint8_t, kHeaderSize + kFdMaxLength + 1> buffer{};
    // Bounded: at most a handful of malformed datagrams are skipped per call.
    for (int attempt = 0; attempt < 16; ++attempt) {
        const ssize_t received = ::recv(socket_, buffer.data(), buffer.size(), 0);
        if (received < 0) {
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                return IoResult::kWouldBlock;
            }
            if (errno == EINTR) {
                continue;
            }
            ++counters_.io_errors;
            return IoResult::kError;
        }
        if (!decode(buffer.data(), static_cast<std::size_t>(received), frame)) {
            ++counters_.rx_dropped;
            continue;
        }
        frame.receive_time_ns = monotonicNowNs();
        if (frame.isError()) {
            ++counters_.rx_error_frames;
            state_.onErrorFrame(frame, frame.receive_time_ns);
        } else {
            ++counters_.rx_frames;
        }
        return IoResult::kOk;
    }
    return IoResult::kWouldBlock;
}

IoResult UdpBus::write(const CanFrame& frame) noexcept {
    std::array<std::uint8_t, kHeaderSize + kFdMaxLength> buffer{};
    const std::size_t size =
        encode(frame, static_cast<std::uint8_t>(slot_), buffer.data(), buffer.size());
    if (size == 0) {
        ++counters_.tx_refused;
        return IoResult::kInvalid;
    }
    if (!frame.isError() && !state_.mayTransmit(monotonicNowNs())) {
        ++counters_.tx_refused;
        return IoResult::kBusOff;
    }
    bool backpressure = false;
    bool failed = false;
    for (std::uint16_t slot = 0; slot < config_.slots; ++slot) {
        if (slot == slot_) {
            continue;
        }
        const sockaddr_in address = loopbackAddress(config_.base_port + slot);
        const ssize_t sent = ::sendto(socket_, buffer.data(), size, 0,
                                      reinterpret_cast<const sockaddr*>(&address), sizeof(address));
        if (sent < 0) {
            if (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS) {
                backpressure = true;
            } else if (errno != ECONNREFUSED) {
                failed = true;
            }
        }
    }
    if (backpressure) {
        ++counters_.tx_backpressure;
        return IoResult::kWouldBlock;
    }
    if (failed) {
        ++counters_.io_errors;
        return IoResult::kError;
    }
    ++counters_.tx_frames;
    return IoResult::kOk;
}

}  // namespace haptic::can
