// The project's one percentile rule (haptic/common/statistics.hpp): the exact form for
// reports and the RT histogram must agree with each other and with the nearest-rank
// definition, so status figures and benchmark rows are comparable.
#include "haptic/common/statistics.hpp"

#include <gmock/gmock.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace haptic::common {
namespace {

using ::testing::DoubleEq;
using ::testing::Eq;
using ::testing::Optional;

TEST(NearestRank, IsTheCeilOfQTimesNOneBased) {
    EXPECT_THAT(nearestRankIndex(0.50, 100), Eq(49U));  // the 50th of 100
    EXPECT_THAT(nearestRankIndex(0.99, 100), Eq(98U));  // the 99th
    EXPECT_THAT(nearestRankIndex(0.99, 101), Eq(99U));  // ceil(99.99) = 100th
    EXPECT_THAT(nearestRankIndex(0.999, 1000), Eq(998U));
    EXPECT_THAT(nearestRankIndex(0.0, 10), Eq(0U));  // never below the first
    EXPECT_THAT(nearestRankIndex(1.0, 10), Eq(9U));  // never past the last
    EXPECT_THAT(nearestRankIndex(0.5, 1), Eq(0U));
}

TEST(Percentile, IsASampleThatOccurredWhateverTheOrder) {
    std::vector<double> samples;
    for (int i = 100; i >= 1; --i) {
        samples.push_back(static_cast<double>(i));
    }
    std::vector<double> copy = samples;
    EXPECT_THAT(percentile(copy, 0.50), DoubleEq(50.0));
    copy = samples;
    EXPECT_THAT(percentile(copy, 0.99), DoubleEq(99.0));
    copy = samples;
    EXPECT_THAT(percentile(copy, 1.0), DoubleEq(100.0));
    std::vector<double> empty;
    EXPECT_THAT(percentile(empty, 0.99), DoubleEq(0.0));
}

TEST(Summarize, AgreesWithPercentileAndKeepsTheMaximum) {
    std::vector<double> samples;
    for (int i = 0; i < 1000; ++i) {
        samples.push_back(static_cast<double>((i * 7919) % 1000));  // 0..999 shuffled
    }
    std::vector<double> for_percentile = samples;
    const PercentileSummary sut = summarize(samples);
    EXPECT_THAT(sut.count, Eq(1000U));
    EXPECT_THAT(sut.p50, DoubleEq(percentile(for_percentile, 0.50)));
    EXPECT_THAT(sut.p50, DoubleEq(499.0));
    EXPECT_THAT(sut.p99, DoubleEq(989.0));
    EXPECT_THAT(sut.p999, DoubleEq(998.0));
    EXPECT_THAT(sut.max, DoubleEq(999.0));
    std::vector<double> empty;
    EXPECT_THAT(summarize(empty).count, Eq(0U));
}

TEST(NearestRankBin, FindsTheBinOrReportsOverflow) {
    const std::array<std::uint64_t, 4> counts{10, 80, 9, 1};  // 100 samples in range
    EXPECT_THAT(nearestRankBin(counts, 100, 0.50), Optional(1U));
    EXPECT_THAT(nearestRankBin(counts, 100, 0.99), Optional(2U));
    EXPECT_THAT(nearestRankBin(counts, 100, 1.0), Optional(3U));
    // 100 more samples beyond the last bin: the p99 lies among them.
    EXPECT_THAT(nearestRankBin(counts, 200, 0.99), Eq(std::nullopt));
    EXPECT_THAT(nearestRankBin(counts, 0, 0.5), Eq(std::nullopt));
}

TEST(FixedBinHistogram, AgreesWithTheExactRuleToOneBin) {
    FixedBinHistogram<2000> sut;
    std::vector<double> samples;
    for (int i = 0; i < 5000; ++i) {
        const double value = 0.37 * static_cast<double>((i * 613) % 5000);  // 0..1850
        sut.add(value);
        samples.push_back(value);
    }
    for (const double q : {0.5, 0.9, 0.99, 0.999}) {
        std::vector<double> copy = samples;
        const double exact = percentile(copy, q);
        // The histogram reports the upper edge of the bin that holds the exact sample.
        EXPECT_GE(sut.quantile(q), exact) << q;
        EXPECT_LE(sut.quantile(q), exact + 1.0) << q;
    }
    EXPECT_THAT(sut.count(), Eq(5000U));
}

TEST(FixedBinHistogram, ValuesPastTheLastBinShowAsTheExactMaximum) {
    FixedBinHistogram<10> sut;
    sut.add(2.5);
    sut.add(50.0);
    sut.add(-3.0);  // clamped to 0
    EXPECT_THAT(sut.quantile(1.0), DoubleEq(50.0));
    EXPECT_THAT(sut.quantile(0.5), DoubleEq(3.0));
    EXPECT_THAT(sut.max(), DoubleEq(50.0));
    sut.reset();
    EXPECT_THAT(sut.count(), Eq(0U));
    EXPECT_THAT(sut.quantile(0.99), DoubleEq(0.0));
}

}  // namespace
}  // namespace haptic::common
