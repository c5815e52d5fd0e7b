#pragma once

#include <filesystem>
#include <string>

namespace haptic::process {

// A PM QoS request for the CPUs' wake-up latency: while it is held the kernel keeps every CPU
// out of idle states that take longer than `latency_us` to leave (0: polling idle only). A
// thread that sleeps between its periods then wakes on a CPU that was not halted, so its wake-up
// and its first microseconds of work are not paid for again each period (docs/hapticd.md,
// "CPU wake-up latency"). The request is the open file: it lasts until this object is destroyed
// or the process ends, however it ends, and several holders' requests combine to the lowest.
class CpuLatencyRequest {
  public:
    static constexpr const char* kDevicePath = "/dev/cpu_dma_latency";

    CpuLatencyRequest() = default;  // no request
    // Opens `device` and writes the request. On failure (or a negative latency) holds nothing
    // and error() says why, naming the file and the system's reason.
    explicit CpuLatencyRequest(int latency_us, const std::filesystem::path& device = kDevicePath);
    ~CpuLatencyRequest();
    CpuLatencyRequest(CpuLatencyRequest&& other) noexcept;
    CpuLatencyRequest& operator=(CpuLatencyRequest&& other) noexcept;
    CpuLatencyRequest(const CpuLatencyRequest&) = delete;
    CpuLatencyRequest& operator=(const CpuLatencyRequest&) = delete;

    [[nodiscard]] bool held() const noexcept { return fd_ >= 0; }
    [[nodiscard]] int latencyUs() const noexcept { return latency_us_; }
    [[nodiscard]] const std::string& error() const noexcept { return error_; }

  private:
    void release() noexcept;

    int fd_{-1};
    int latency_us_{-1};
    std::string error_;
};

}  // namespace haptic::process
