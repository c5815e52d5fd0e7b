#include "haptic/ipc/roudi_config_check.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <tuple>

#include "haptic/ipc/ipc_error.hpp"
#include "haptic/msgs/messages.hpp"
#include "iceoryx_hoofs/log/logmanager.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/roudi/roudi_config_toml_file_provider.hpp"

namespace haptic::ipc {

namespace {

// iceoryx 2.0's MemPool: chunks of at least its 8-byte alignment, and at least one of them.
constexpr std::uint32_t kSmallestChunkBytes = 8;
// A chunk's payload follows its header at the header's alignment: a message aligned no more
// strictly needs no more than its size.
static_assert(std::apply(
    [](auto... message) {
        return ((alignof(typename decltype(message)::type) <= alignof(iox::mepoo::ChunkHeader)) &&
                ...);
    },
    msgs::kShmMessageTypes));

constexpr auto kSimLinkMessages = std::apply(
    [](auto... message) {
        return std::array{
            ShmMessageSize{message.name, sizeof(typename decltype(message)::type)}...};
    },
    msgs::kShmMessageTypes);

}  // namespace

std::span<const ShmMessageSize> simLinkShmMessages() {
    return kSimLinkMessages;
}

void checkRoudiConfig(const std::filesystem::path& roudi_config,
                      std::span<const ShmMessageSize> messages) {
    const std::string where = "iceoryx.roudi_config " + roudi_config.string();
    const std::string path = roudi_config.string();
    if (path.size() > iox::roudi::ConfigFilePathString_t::capacity()) {
        throw IpcError(where + ": path longer than iceoryx's " +
                       std::to_string(iox::roudi::ConfigFilePathString_t::capacity()) +
                       " characters");
    }
    // The parser reports through iceoryx's logger, verbose by default; its warnings (a TOML
    // error's line and column) stay visible.
    iox::log::LogManager::GetLogManager().SetDefaultLogLevel(
        iox::log::LogLevel::kWarn, iox::log::LogLevelOutput::kHideLogLevel);
    iox::config::CmdLineArgs_t arguments;
    arguments.configFilePath =
        iox::roudi::ConfigFilePathString_t(iox::cxx::TruncateToCapacity, path.c_str());
    iox::config::TomlRouDiConfigFileProvider provider(arguments);
    const auto parsed = provider.parse();
    if (parsed.has_error()) {
        const auto index = static_cast<std::size_t>(parsed.get_error());
        throw IpcError(where + ": not a RouDi configuration iceoryx accepts (" +
                       iox::roudi::ROUDI_CONFIG_FILE_PARSE_ERROR_STRINGS[index] + ")");
    }
    std::uint32_t largest_pool = 0;
    for (const auto& segment : parsed.value().m_sharedMemorySegments) {
        for (const auto& pool : segment.m_mempoolConfig.m_mempoolConfig) {
            // What iox-roudi's memory manager refuses at start (it terminates on them).
            if (pool.m_chunkCount == 0 || pool.m_size < kSmallestChunkBytes) {
                throw IpcError(where + ": a mempool of size " + std::to_string(pool.m_size) +
                               " and count " + std::to_string(pool.m_chunkCount) +
                               ", which iox-roudi refuses (size at least " +
                               std::to_string(kSmallestChunkBytes) + ", count at least 1)");
            }
            largest_pool = std::max(largest_pool, pool.m_size);
        }
    }
    const auto largest = std::max_element(
        messages.begin(), messages.end(),
        [](const ShmMessageSize& a, const ShmMessageSize& b) { return a.bytes < b.bytes; });
    if (largest != messages.end() && largest->bytes > largest_pool) {
        throw IpcError(where + ": no mempool holds a " + std::string(largest->type) + " (" +
                       std::to_string(largest->bytes) + " bytes); the largest pool's chunks are " +
                       std::to_string(largest_pool) +
                       " bytes. Add a [[segment.mempool]] with size >= " +
                       std::to_string(largest->bytes) + " and restart iox-roudi with the file");
    }
}

}  // namespace haptic::ipc
