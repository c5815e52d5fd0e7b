#include "haptic/process/cpu_latency.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <utility>

#include "open_files.hpp"

namespace haptic::process {
namespace {

namespace fs = std::filesystem;

// How many of this process's open files are `file`.
int openCount(const fs::path& file) {
    return haptic::testing::openCount(::getpid(), file);
}

class CpuLatencyRequestTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("cpu_latency_test." + std::to_string(::getpid()));
        fs::create_directories(dir_);
        file_ = dir_ / "cpu_dma_latency";
        std::ofstream(file_).close();
    }
    void TearDown() override { fs::remove_all(dir_); }

    fs::path dir_;
    fs::path file_;
};

// The kernel takes four bytes as a binary value; the request lasts as long as the file is open.
TEST_F(CpuLatencyRequestTest, WritesTheValueAsFourBinaryBytesAndHoldsTheFileUntilDestroyed) {
    {
        const CpuLatencyRequest request(7, file_);
        ASSERT_TRUE(request.held()) << request.error();
        EXPECT_EQ(request.latencyUs(), 7);
        EXPECT_EQ(openCount(file_), 1);
        EXPECT_EQ(haptic::testing::readCpuLatencyUs(file_), 7);
        EXPECT_EQ(fs::file_size(file_), 4U);
    }
    EXPECT_EQ(openCount(file_), 0);
}

TEST_F(CpuLatencyRequestTest, AMoveCarriesTheRequestAndTheSourceHoldsNothing) {
    CpuLatencyRequest first(0, file_);
    CpuLatencyRequest second(std::move(first));
    EXPECT_FALSE(first.held());  // NOLINT(bugprone-use-after-move): what a move leaves
    EXPECT_TRUE(second.held());
    EXPECT_EQ(second.latencyUs(), 0);
    CpuLatencyRequest third;
    EXPECT_FALSE(third.held());
    third = std::move(second);
    EXPECT_TRUE(third.held());
    EXPECT_EQ(openCount(file_), 1);
}

TEST_F(CpuLatencyRequestTest, ANegativeLatencyIsNoRequest) {
    const CpuLatencyRequest request(-1, file_);
    EXPECT_FALSE(request.held());
    EXPECT_EQ(openCount(file_), 0);
    EXPECT_EQ(request.error(), "a CPU latency request of -1 us: expected 0 or more");
}

TEST_F(CpuLatencyRequestTest, AFileItCannotOpenIsNamedWithTheSystemsReason) {
    const CpuLatencyRequest request(0, dir_ / "missing" / "cpu_dma_latency");
    EXPECT_FALSE(request.held());
    EXPECT_EQ(request.latencyUs(), -1);
    EXPECT_EQ(request.error(), (dir_ / "missing" / "cpu_dma_latency").string() +
                                   ": cannot open: No such file or directory");
}

// The kernel's own device: while the request is held, reading it gives the combined request
// of every holder, which is at most this one.
TEST(CpuLatencyRequestDevice, TheKernelHoldsTheRequestWhileItIsOpen) {
    if (::access(CpuLatencyRequest::kDevicePath, W_OK) != 0) {
        GTEST_SKIP() << "cannot write " << CpuLatencyRequest::kDevicePath;
    }
    const CpuLatencyRequest request(3);
    ASSERT_TRUE(request.held()) << request.error();
    const auto combined = haptic::testing::readCpuLatencyUs(CpuLatencyRequest::kDevicePath);
    ASSERT_TRUE(combined.has_value()) << "fewer than four bytes read";
    EXPECT_GE(*combined, 0);
    EXPECT_LE(*combined, 3);
}

}  // namespace
}  // namespace haptic::process
