// Encode + decode of one device frame (the codec work per frame on the 1 kHz path).
//
//   ninja -C build/release drivers_frame_benchmark
//   build/release/tests/bench/drivers_frame_benchmark
//
// Two views per frame type:
//   BM_<frame>                 Google Benchmark's time per encode+decode, repeated 50 times;
//                              the p50/p99 rows are over the 50 repetition means.
//   BM_<frame>_PerFrameSamples every single encode+decode timed with steady_clock; the
//                              p50_ns/p99_ns counters are over 200 000 frames and include the
//                              clock read (~15-25 ns here), so they overstate the codec cost.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "haptic/common/statistics.hpp"
#include "haptic/config/device.hpp"
#include "haptic/protocol/exoskeleton_protocol.hpp"
#include "haptic/protocol/thimble_protocol.hpp"

namespace {

using namespace haptic;

const config::DeviceConfig& exoskeleton() {
    static const auto device =
        config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/exoskeleton.yaml");
    return device;
}
const config::DeviceConfig& thimble() {
    static const auto device =
        config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/thimble.yaml");
    return device;
}

// One encode + decode; returns false if the frame did not come back as sent.
struct ExoCommand {
    protocol::ExoskeletonCodec tx{exoskeleton()}, rx{exoskeleton()};
    bool operator()(int i) {
        can::CanFrame frame;
        const bool ok = tx.encodeCommand({0.001 * (i % 20000) - 10.0, true}, frame);
        return ok && rx.decode(frame).type == protocol::ExoskeletonMessage::Type::kCommand;
    }
};
struct ExoActuatorState {
    protocol::ExoskeletonCodec tx{exoskeleton()}, rx{exoskeleton()};
    bool operator()(int i) {
        can::CanFrame frame;
        const bool ok = tx.encodeActuatorState(
            {1e-6 * (i % 20000), 0.001 * (i % 20000) - 10.0, protocol::kExoEnabled, 3}, frame);
        return ok && rx.decode(frame).type == protocol::ExoskeletonMessage::Type::kActuatorState;
    }
};
struct ExoEncoders {
    protocol::ExoskeletonCodec tx{exoskeleton()}, rx{exoskeleton()};
    bool operator()(int i) {
        can::CanFrame frame;
        const double q = 1e-4 * (i % 10000);
        const bool ok = tx.encodeEncoders({{q, q, q}}, frame);
        return ok && rx.decode(frame).type == protocol::ExoskeletonMessage::Type::kEncoders;
    }
};
struct ThimbleCommand {
    protocol::ThimbleCodec tx{thimble()}, rx{thimble()};
    bool operator()(int i) {
        can::CanFrame frame;
        const double q = 1e-4 * (i % 10000);
        const bool ok = tx.encodeCommand({{q, q, q}}, frame);
        return ok && rx.decode(frame).type == protocol::ThimbleMessage::Type::kCommand;
    }
};
struct ThimbleState {
    protocol::ThimbleCodec tx{thimble()}, rx{thimble()};
    bool operator()(int i) {
        can::CanFrame frame;
        const double q = 1e-4 * (i % 10000);
        const bool ok = tx.encodeState({{q, q, q}}, frame);
        return ok && rx.decode(frame).type == protocol::ThimbleMessage::Type::kState;
    }
};
struct Heartbeat {
    protocol::ExoskeletonCodec tx{exoskeleton()}, rx{exoskeleton()};
    bool operator()(int i) {
        can::CanFrame frame;
        tx.encodeHeartbeat({protocol::DeviceMode::kOperational, 0, static_cast<std::uint32_t>(i)},
                           frame);
        return rx.decode(frame).type == protocol::ExoskeletonMessage::Type::kHeartbeat;
    }
};

template <typename Codec>
void BM_EncodeDecode(benchmark::State& state) {
    Codec codec;
    int i = 0;
    for (auto _ : state) {
        const bool ok = codec(i++);
        benchmark::DoNotOptimize(ok);
        if (!ok) {
            state.SkipWithError("frame did not round-trip");
            break;
        }
    }
}

template <typename Codec>
void BM_PerFrameSamples(benchmark::State& state) {
    constexpr int kFrames = 200'000;
    std::vector<double> samples(kFrames);
    Codec codec;
    for (auto _ : state) {
        for (int i = 0; i < kFrames; ++i) {
            const auto start = std::chrono::steady_clock::now();
            const bool ok = codec(i);
            const auto stop = std::chrono::steady_clock::now();
            benchmark::DoNotOptimize(ok);
            samples[static_cast<std::size_t>(i)] =
                std::chrono::duration<double, std::nano>(stop - start).count();
        }
    }
    state.counters["p50_ns"] = common::percentile(samples, 0.50);
    state.counters["p99_ns"] = common::percentile(samples, 0.99);
    state.counters["max_ns"] = *std::max_element(samples.begin(), samples.end());
}

double p50(const std::vector<double>& v) {
    std::vector<double> copy = v;
    return common::percentile(copy, 0.50);
}
double p99(const std::vector<double>& v) {
    std::vector<double> copy = v;
    return common::percentile(copy, 0.99);
}

#define HAPTIC_FRAME_BENCHMARK(Codec)   \
    BENCHMARK(BM_EncodeDecode<Codec>)   \
        ->Name("BM_" #Codec)            \
        ->Repetitions(50)               \
        ->ComputeStatistics("p50", p50) \
        ->ComputeStatistics("p99", p99) \
        ->ReportAggregatesOnly(true);   \
    BENCHMARK(BM_PerFrameSamples<Codec>)->Name("BM_" #Codec "_PerFrameSamples")->Iterations(1)

HAPTIC_FRAME_BENCHMARK(ExoCommand);
HAPTIC_FRAME_BENCHMARK(ExoActuatorState);
HAPTIC_FRAME_BENCHMARK(ExoEncoders);
HAPTIC_FRAME_BENCHMARK(ThimbleCommand);
HAPTIC_FRAME_BENCHMARK(ThimbleState);
HAPTIC_FRAME_BENCHMARK(Heartbeat);

}  // namespace
