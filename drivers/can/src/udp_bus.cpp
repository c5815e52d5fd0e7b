#include "haptic/can/udp_bus.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "haptic/common/clock.hpp"

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
    // The default receive buffer (net.core.rmem_default, 208 KiB here) holds about 230
    // datagrams, since each small frame is charged a whole buffer: some 50 ms of the
    // emulated devices' traffic. A reader starved longer (a loaded test machine) lost a burst
    // and saw an alive-counter jump. 1 MiB, capped by net.core.rmem_max; best effort, as the
    // default still works when the reader keeps up.
    const int receive_buffer_bytes = 1 << 20;
    (void)::setsockopt(socket_, SOL_SOCKET, SO_RCVBUF, &receive_buffer_bytes,
                       sizeof(receive_buffer_bytes));
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

IoResult UdpBus::receiveBatch() noexcept {
    // One spare byte per buffer so that an oversized datagram shows up as a wrong size.
    constexpr std::size_t kBufferSize = kHeaderSize + kFdMaxLength + 1;
    std::array<std::array<std::uint8_t, kBufferSize>, kReceiveBatch> buffers;
    std::array<iovec, kReceiveBatch> vectors{};
    std::array<mmsghdr, kReceiveBatch> messages{};
    for (std::size_t i = 0; i < kReceiveBatch; ++i) {
        vectors[i] = {buffers[i].data(), buffers[i].size()};
        messages[i].msg_hdr.msg_iov = &vectors[i];
        messages[i].msg_hdr.msg_iovlen = 1;
    }
    pending_count_ = 0;
    pending_next_ = 0;
    // Bounded: a signal interrupts at most a couple of attempts.
    for (int attempt = 0; attempt < 4; ++attempt) {
        const int received =
            ::recvmmsg(socket_, messages.data(), kReceiveBatch, MSG_DONTWAIT, nullptr);
        if (received < 0) {
            if (errno == EINTR) {
                continue;
            }
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                return IoResult::kWouldBlock;
            }
            ++counters_.io_errors;
            return IoResult::kError;
        }
        const std::int64_t now_ns = common::monotonicNowNs();
        last_batch_was_short_ = static_cast<std::size_t>(received) < kReceiveBatch;
        for (int i = 0; i < received; ++i) {
            CanFrame& frame = pending_[pending_count_];
            if (!decode(buffers[i].data(), messages[i].msg_len, frame)) {
                ++counters_.rx_dropped;
                continue;
            }
            frame.receive_time_ns = now_ns;
            ++pending_count_;
        }
        if (pending_count_ > 0) {
            return IoResult::kOk;
        }
        // Only malformed datagrams: look once more, they may have hidden good ones.
        if (last_batch_was_short_) {
            return IoResult::kWouldBlock;
        }
    }
    return pending_count_ > 0 ? IoResult::kOk : IoResult::kWouldBlock;
}

IoResult UdpBus::read(CanFrame& frame) noexcept {
    if (pending_next_ == pending_count_) {
        if (pending_count_ > 0 && last_batch_was_short_) {
            // The batch just handed out emptied the socket; see the header.
            pending_count_ = 0;
            pending_next_ = 0;
            return IoResult::kWouldBlock;
        }
        const IoResult result = receiveBatch();
        if (result != IoResult::kOk) {
            return result;
        }
    }
    frame = pending_[pending_next_++];
    if (frame.isError()) {
        ++counters_.rx_error_frames;
        state_.onErrorFrame(frame, frame.receive_time_ns);
    } else {
        ++counters_.rx_frames;
    }
    return IoResult::kOk;
}

IoResult UdpBus::write(const CanFrame& frame) noexcept {
    std::array<std::uint8_t, kHeaderSize + kFdMaxLength> buffer{};
    const std::size_t size =
        encode(frame, static_cast<std::uint8_t>(slot_), buffer.data(), buffer.size());
    if (size == 0) {
        ++counters_.tx_refused;
        return IoResult::kInvalid;
    }
    if (!frame.isError() && !state_.mayTransmit(common::monotonicNowNs())) {
        ++counters_.tx_refused;
        return IoResult::kBusOff;
    }
    // The same datagram to every other port of the block, in one system call.
    iovec vector{buffer.data(), size};
    std::array<sockaddr_in, kMaxSlots> addresses{};
    std::array<mmsghdr, kMaxSlots> messages{};
    unsigned int count = 0;
    for (std::uint16_t slot = 0; slot < config_.slots; ++slot) {
        if (slot == slot_) {
            continue;
        }
        addresses[count] = loopbackAddress(config_.base_port + slot);
        messages[count].msg_hdr.msg_name = &addresses[count];
        messages[count].msg_hdr.msg_namelen = sizeof(sockaddr_in);
        messages[count].msg_hdr.msg_iov = &vector;
        messages[count].msg_hdr.msg_iovlen = 1;
        ++count;
    }
    bool backpressure = false;
    bool failed = false;
    // sendmmsg() stops at the first datagram that fails; note why and go on after it.
    // Bounded: every pass but a few interrupted ones advances by at least one datagram.
    unsigned int next = 0;
    int interruptions = 0;
    while (next < count) {
        const int sent = ::sendmmsg(socket_, messages.data() + next, count - next, 0);
        if (sent > 0) {
            next += static_cast<unsigned int>(sent);
            continue;
        }
        if (sent < 0 && errno == EINTR && ++interruptions <= 4) {
            continue;
        }
        if (sent < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS)) {
            backpressure = true;
        } else if (sent == 0 || errno != ECONNREFUSED) {
            failed = true;
        }
        ++next;
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
