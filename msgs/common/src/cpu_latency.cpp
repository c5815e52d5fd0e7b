#include "haptic/process/cpu_latency.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>

namespace haptic::process {

CpuLatencyRequest::CpuLatencyRequest(int latency_us, const std::filesystem::path& device) {
    if (latency_us < 0) {
        error_ =
            "a CPU latency request of " + std::to_string(latency_us) + " us: expected 0 or more";
        return;
    }
    const auto failed = [&](const char* what, int error) {
        error_ = device.string() + ": " + what + ": " + std::strerror(error);
    };
    fd_ = ::open(device.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd_ < 0) {
        failed("cannot open", errno);
        return;
    }
    // The kernel reads a write of exactly four bytes as a binary value (any other length as
    // hexadecimal text).
    const std::int32_t value = latency_us;
    if (const ssize_t written = ::write(fd_, &value, sizeof(value));
        written != static_cast<ssize_t>(sizeof(value))) {
        failed("cannot write the request", written < 0 ? errno : EIO);
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
