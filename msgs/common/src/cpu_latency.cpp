#include "haptic/process/cpu_latency.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <utility>

namespace haptic::process {

CpuLatencyRequest::CpuLatencyRequest(int latency_us, const std::filesystem::path& device) {
    const auto failed = [&](const char* what) {
        error_ = device.string() + ": " + what + ": " + std::strerror(errno);
    };
    fd_ = ::open(device.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd_ < 0) {
        failed("cannot open");
        return;
    }
    // The kernel reads a write of exactly four bytes as a binary value (any other length as
    // hexadecimal text).
    const std::int32_t value = latency_us;
    if (::write(fd_, &value, sizeof(value)) != static_cast<ssize_t>(sizeof(value))) {
        failed("cannot write the request");
        release();
        return;
    }
    latency_us_ = latency_us;
}

CpuLatencyRequest::~CpuLatencyRequest() {
    release();
}

CpuLatencyRequest::CpuLatencyRequest(CpuLatencyRequest&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      latency_us_(std::exchange(other.latency_us_, -1)),
      error_(std::move(other.error_)) {}

CpuLatencyRequest& CpuLatencyRequest::operator=(CpuLatencyRequest&& other) noexcept {
    if (this != &other) {
        release();
        fd_ = std::exchange(other.fd_, -1);
        latency_us_ = std::exchange(other.latency_us_, -1);
        error_ = std::move(other.error_);
    }
    return *this;
}

void CpuLatencyRequest::release() noexcept {
    if (fd_ >= 0) {
        (void)::close(fd_);
        fd_ = -1;
    }
}

}  // namespace haptic::process
