#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "latency_stats.hpp"

namespace haptic::bench {
namespace {

TEST(LoopBenchStats, NearestRankPercentilesOfRawSamples) {
    std::vector<double> samples;
    for (int i = 1000; i >= 1; --i) {
        samples.push_back(static_cast<double>(i));
    }
    const auto summary = summarize(samples);
    EXPECT_EQ(summary.count, 1000U);
    EXPECT_DOUBLE_EQ(summary.p50, 500.0);
    EXPECT_DOUBLE_EQ(summary.p99, 990.0);
    EXPECT_DOUBLE_EQ(summary.p999, 999.0);
    EXPECT_DOUBLE_EQ(summary.max, 1000.0);
}

// The shape of `cyclictest -q -h 8` output (rt-tests 2.4), trimmed to a small range.
const std::string kHistogram =
    "# /dev/cpu_dma_latency set to 0us\n"
    "# Histogram\n"
    "000000 000000\n"
    "000001 000000\n"
    "000002 000500\n"
    "000003 000400\n"
    "000004 000080\n"
    "000005 000009\n"
    "000006 000000\n"
    "000007 000000\n"
    "# Total: 000000989\n"
    "# Min Latencies: 00002\n"
    "# Avg Latencies: 00002\n"
    "# Max Latencies: 00950\n"
    "# Histogram Overflows: 00011\n"
    "# Histogram Overflow at cycle number:\n"
    "# Thread 0: 00012 00105\n";

TEST(LoopBenchStats, CyclictestHistogramPercentilesCountOverflowsAsSlowest) {
    std::string error;
    const auto histogram = parseCyclictestOutput(kHistogram, error);
    ASSERT_TRUE(histogram.has_value()) << error;
    const LatencySummary summary = summarize(*histogram);
    EXPECT_EQ(summary.count, 1000U);
    EXPECT_EQ(summary.overflows, 11U);
    EXPECT_DOUBLE_EQ(summary.p50, 2.0);  // 500th of 1000
    EXPECT_DOUBLE_EQ(summary.p99, 8.0);  // 990th falls among the overflows: range top
    EXPECT_DOUBLE_EQ(summary.p999, 8.0);
    EXPECT_DOUBLE_EQ(summary.max, 950.0);
}

// The bench interleaves cyclictest and hapticd in rounds; the rounds' histograms add up to
// one, whose percentiles are those of all samples together.
TEST(LoopBenchStats, RoundsOfCyclictestMergeIntoOneHistogram) {
    std::string error;
    auto total = parseCyclictestOutput(kHistogram, error);
    ASSERT_TRUE(total.has_value()) << error;
    const std::string slow_round =
        "000000 000000\n000001 000000\n000002 000000\n000003 000000\n000004 000000\n"
        "000005 000000\n000006 000000\n000007 001000\n# Max Latencies: 00007\n"
        "# Histogram Overflows: 00000\n";
    const auto round = parseCyclictestOutput(slow_round, error);
    ASSERT_TRUE(round.has_value()) << error;
    merge(*total, *round);
    const LatencySummary summary = summarize(*total);
    EXPECT_EQ(summary.count, 2000U);
    EXPECT_EQ(summary.overflows, 11U);
    // Below 7 us: 989 samples, all from the first round.
    EXPECT_DOUBLE_EQ(summary.p50, 7.0);   // 1000th of 2000
    EXPECT_DOUBLE_EQ(summary.p99, 7.0);   // 1980th of the 1989 in range
    EXPECT_DOUBLE_EQ(summary.p999, 8.0);  // 1998th: among the 11 overflows, the range top
    EXPECT_DOUBLE_EQ(summary.max, 950.0);
}

TEST(LoopBenchStats, OutputWithoutHistogramIsAnError) {
    std::string error;
    EXPECT_FALSE(parseCyclictestOutput("T: 0 ( 1) P:80 I:1000 C: 10 Min: 3\n", error));
    EXPECT_NE(error.find("no histogram"), std::string::npos);
}

}  // namespace
}  // namespace haptic::bench
