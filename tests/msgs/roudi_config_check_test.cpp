// iceoryx.roudi_config: the RouDi configuration hapticd and handsim check at start (the real
// file through iceoryx's own parser; no RouDi is needed for the check).

#include "haptic/ipc/roudi_config_check.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "haptic/ipc/iceoryx_runtime.hpp"
#include "haptic/ipc/ipc_error.hpp"

namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

const fs::path kShippedRoudiConfig = fs::path(HAPTIC_CONFIG_DIR) / "roudi.toml";

class RoudiConfigCheck : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("roudi_config_check_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    fs::path write(const std::string& text) {
        const fs::path path = dir_ / "roudi.toml";
        std::ofstream(path) << text;
        return path;
    }
    static std::string pools(std::initializer_list<std::pair<int, int>> size_count) {
        std::string text = "[general]\nversion = 1\n\n[[segment]]\n";
        for (const auto& [size, count] : size_count) {
            text += "\n[[segment.mempool]]\nsize = " + std::to_string(size) +
                    "\ncount = " + std::to_string(count) + "\n";
        }
        return text;
    }
    static std::string messageOf(const fs::path& path) {
        try {
            haptic::ipc::checkRoudiConfig(path);
        } catch (const haptic::ipc::IpcError& error) {
            return error.what();
        }
        return {};
    }

    fs::path dir_;
};

haptic::ipc::ShmMessageSize largestMessage() {
    const auto messages = haptic::ipc::simLinkShmMessages();
    return *std::max_element(messages.begin(), messages.end(),
                             [](const auto& a, const auto& b) { return a.bytes < b.bytes; });
}

TEST_F(RoudiConfigCheck, TheShippedRoudiConfigCarriesEveryMessage) {
    EXPECT_NO_THROW(haptic::ipc::checkRoudiConfig(kShippedRoudiConfig));
}

TEST_F(RoudiConfigCheck, EveryMessageTwinIsListed) {
    EXPECT_EQ(haptic::ipc::simLinkShmMessages().size(), 9U);
    for (const auto& message : haptic::ipc::simLinkShmMessages()) {
        EXPECT_GT(message.bytes, 0U) << message.type;
    }
}

TEST_F(RoudiConfigCheck, PoolsTooSmallForTheLargestMessageNameItAndTheSizeNeeded) {
    const auto largest = largestMessage();
    ASSERT_GT(largest.bytes, 1024U);
    const fs::path path = write(pools({{1024, 512}, {static_cast<int>(largest.bytes) - 8, 4}}));
    const std::string message = messageOf(path);
    EXPECT_THAT(message, AllOf(HasSubstr("iceoryx.roudi_config " + path.string()),
                               HasSubstr("no mempool holds a " + std::string(largest.type)),
                               HasSubstr(std::to_string(largest.bytes) + " bytes"),
                               HasSubstr(std::to_string(largest.bytes - 8) + " bytes")));
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

TEST_F(RoudiConfigCheck, PoolsIoxRoudiRefusesAreNamed) {
    EXPECT_THAT(messageOf(write(pools({{1024, 512}, {65536, 0}}))),
                AllOf(HasSubstr("a mempool of size 65536 and count 0"),
                      HasSubstr("which iox-roudi refuses")));
    EXPECT_THAT(messageOf(write(pools({{4, 16}, {65536, 8}}))),
                HasSubstr("a mempool of size 4 and count 16"));
}

// Sizes only: one chunk of the largest message's size passes (how many the queues need is
// not known before the processes subscribe).
TEST_F(RoudiConfigCheck, APoolExactlyTheLargestMessagesSizeIsEnoughForItsSize) {
    const auto largest = largestMessage();
    EXPECT_NO_THROW(haptic::ipc::checkRoudiConfig(
        write(pools({{1024, 512}, {static_cast<int>(largest.bytes), 1}}))));
}

TEST_F(RoudiConfigCheck, AFileIceoryxRefusesIsNamedWithIceoryxsReason) {
    EXPECT_THAT(messageOf(write("[[segment]]\n[[segment.mempool]]\nsize = 65536\ncount = 8\n")),
                AllOf(HasSubstr("not a RouDi configuration"), HasSubstr("NO_GENERAL_SECTION")));
    EXPECT_THAT(messageOf(write("[general]\nversion = 1\n[[segment]]\n")),
                HasSubstr("SEGMENT_WITHOUT_MEMPOOL"));
    EXPECT_THAT(messageOf(write("[general\nversion = 1\n")), HasSubstr("EXCEPTION_IN_PARSER"));
}

// The production path: hapticd and handsim call joinRoudi with their file's iceoryx map. The
// check comes before RouDi is probed, so a bad file is reported whether or not RouDi runs.
TEST_F(RoudiConfigCheck, JoiningRoudiChecksTheConfiguredFileFirst) {
    const haptic::config::IceoryxConfig small{write(pools({{1024, 512}}))};
    EXPECT_THROW(
        {
            try {
                (void)haptic::ipc::joinRoudi(true, "roudi_config_check_test", small);
            } catch (const haptic::ipc::IpcError& error) {
                EXPECT_THAT(error.what(), HasSubstr("no mempool holds"));
                throw;
            }
        },
        haptic::ipc::IpcError);
    // Over DDS there is no RouDi to check for.
    EXPECT_EQ(haptic::ipc::joinRoudi(false, "roudi_config_check_test", small), std::nullopt);
}

}  // namespace
