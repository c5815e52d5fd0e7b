#include "haptic/can/socketcan_bus.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "haptic/common/clock.hpp"

namespace haptic::can {
namespace {

[[noreturn]] void fail(int fd, const std::string& interface, const char* step, int error) {
    if (fd >= 0) {
        ::close(fd);
    }
    std::string reason = std::strerror(error);
    if (error == EAFNOSUPPORT) {
        reason = "kernel has no CAN support (no AF_CAN)";
    } else if (error == ENODEV) {
        reason = "no such interface";
    }
    throw std::runtime_error("socketcan " + interface + ": " + step + ": " + reason);
}

}  // namespace

bool SocketCanBus::kernelSupportsCan() noexcept {
    const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        return false;
    }
    ::close(fd);
    return true;
}

SocketCanBus::SocketCanBus(const SocketCanConfig& config) : fd_(config.fd) {
    state_.setPolicy(config.recovery);
    if (config.interface.empty() || config.interface.size() >= IFNAMSIZ) {
        throw std::runtime_error("socketcan: interface name must be 1-15 characters");
    }
    const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        fail(-1, config.interface, "socket", errno);
    }
    ifreq request{};
    std::strncpy(request.ifr_name, config.interface.c_str(), IFNAMSIZ - 1);
    if (::ioctl(fd, SIOCGIFINDEX, &request) < 0) {
        fail(fd, config.interface, "interface lookup", errno);
    }
    if (!config.receive_ids.empty()) {
        std::vector<can_filter> filters;
        for (std::uint32_t id : config.receive_ids) {
            if ((id & ~kStandardIdMask) != 0) {
                ::close(fd);
                throw std::runtime_error("socketcan " + config.interface +
                                         ": receive id is not an 11-bit id");
            }
            filters.push_back({id, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG});
        }
        if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
                         static_cast<socklen_t>(filters.size() * sizeof(can_filter))) < 0) {
            fail(fd, config.interface, "CAN_RAW_FILTER", errno);
        }
    }
    const can_err_mask_t error_mask = CAN_ERR_MASK;
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &error_mask, sizeof(error_mask)) < 0) {
        fail(fd, config.interface, "CAN_RAW_ERR_FILTER", errno);
    }
    if (config.fd) {
        const int enable = 1;
        if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &enable, sizeof(enable)) < 0) {
            fail(fd, config.interface, "CAN_RAW_FD_FRAMES", errno);
        }
    }
    const int enable_overflow = 1;
    if (::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &enable_overflow, sizeof(enable_overflow)) < 0) {
        fail(fd, config.interface, "SO_RXQ_OVFL", errno);
    }
    sockaddr_can address{};
    address.can_family = AF_CAN;
    address.can_ifindex = request.ifr_ifindex;
    if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) < 0) {
        fail(fd, config.interface, "bind", errno);
    }
    socket_ = fd;
}

SocketCanBus::~SocketCanBus() {
    if (socket_ >= 0) {
        ::close(socket_);
    }
}

IoResult SocketCanBus::read(CanFrame& frame) noexcept {
    canfd_frame raw{};
    iovec io{&raw, sizeof(raw)};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(std::uint32_t))];
    msghdr message{};
    message.msg_iov = &io;
    message.msg_iovlen = 1;
    message.msg_control = control;
    message.msg_controllen = sizeof(control);
    ssize_t received = -1;
    for (int attempt = 0; attempt < 4; ++attempt) {
        received = ::recvmsg(socket_, &message, MSG_DONTWAIT);
        if (received >= 0 || errno != EINTR) {
            break;
        }
    }
    if (received < 0) {
        if (errno == EAGAIN || errno == EWOULDBLOCK) {
            return IoResult::kWouldBlock;
        }
        ++counters_.io_errors;
        return IoResult::kError;
    }
    for (cmsghdr* header = CMSG_FIRSTHDR(&message); header != nullptr;
         header = CMSG_NXTHDR(&message, header)) {
        if (header->cmsg_level == SOL_SOCKET && header->cmsg_type == SO_RXQ_OVFL) {
            std::uint32_t dropped = 0;
            std::memcpy(&dropped, CMSG_DATA(header), sizeof(dropped));
            counters_.rx_overflows += dropped - last_overflow_count_;
            last_overflow_count_ = dropped;
        }
    }
    CanFrame decoded;
    if (received == CANFD_MTU) {
        decoded.flags |= kFlagFd;
        if ((raw.flags & CANFD_BRS) != 0) {
            decoded.flags |= kFlagBitRateSwitch;
        }
    } else if (received != CAN_MTU) {
        ++counters_.rx_dropped;
        return IoResult::kWouldBlock;
    }
    decoded.length = raw.len > kFdMaxLength ? kFdMaxLength : raw.len;
    std::memcpy(decoded.data.data(), raw.data, decoded.length);
    decoded.receive_time_ns = common::monotonicNowNs();
    if ((raw.can_id & CAN_ERR_FLAG) != 0) {
        decoded.flags |= kFlagError;
        decoded.id = raw.can_id & CAN_ERR_MASK;
        frame = decoded;
        ++counters_.rx_error_frames;
        state_.onErrorFrame(frame, decoded.receive_time_ns);
        return IoResult::kOk;
    }
    if ((raw.can_id & CAN_EFF_FLAG) != 0) {
        decoded.flags |= kFlagExtendedId;
        decoded.id = raw.can_id & CAN_EFF_MASK;
    } else {
        decoded.id = raw.can_id & CAN_SFF_MASK;
    }
    if ((raw.can_id & CAN_RTR_FLAG) != 0) {
        decoded.flags |= kFlagRemote;
    }
    frame = decoded;
    ++counters_.rx_frames;
    return IoResult::kOk;
}

IoResult SocketCanBus::write(const CanFrame& frame) noexcept {
    if (!isWellFormed(frame) || frame.isError() || (frame.isFd() && !fd_)) {
        ++counters_.tx_refused;
        return IoResult::kInvalid;
    }
    if (!state_.mayTransmit(common::monotonicNowNs())) {
        ++counters_.tx_refused;
        return IoResult::kBusOff;
    }
    canfd_frame raw{};
    raw.can_id = frame.id;
    if (frame.isExtended()) {
        raw.can_id |= CAN_EFF_FLAG;
    }
    if ((frame.flags & kFlagRemote) != 0) {
        raw.can_id |= CAN_RTR_FLAG;
    }
    raw.len = frame.length;
    if ((frame.flags & kFlagBitRateSwitch) != 0) {
        raw.flags |= CANFD_BRS;
    }
    std::memcpy(raw.data, frame.data.data(), frame.length);
    const std::size_t size = frame.isFd() ? CANFD_MTU : CAN_MTU;
    const ssize_t sent = ::write(socket_, &raw, size);
    if (sent == static_cast<ssize_t>(size)) {
        ++counters_.tx_frames;
        return IoResult::kOk;
    }
    if (sent < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS)) {
        ++counters_.tx_backpressure;
        return IoResult::kWouldBlock;
    }
    ++counters_.io_errors;
    return IoResult::kError;
}

}  // namespace haptic::can
