#include "haptic/ipc/iceoryx_runtime.hpp"

#include <string>

#include "haptic/ipc/ipc_error.hpp"
#include "haptic/ipc/roudi_config_check.hpp"
#include "iceoryx_hoofs/log/logmanager.hpp"
#include "iceoryx_posh/runtime/posh_runtime.hpp"

namespace haptic::ipc {

void initIceoryxRuntime(std::string_view app_name) {
    const RoudiProbe probe = probeRoudi();
    if (!probe.reachable) {
        throw IpcError(probe.reason);
    }
    // iceoryx logs at verbose by default, which would drown our own log.
    iox::log::LogManager::GetLogManager().SetDefaultLogLevel(
        iox::log::LogLevel::kWarn, iox::log::LogLevelOutput::kHideLogLevel);
    const std::string name(app_name);
    iox::runtime::PoshRuntime::initRuntime(
        iox::RuntimeName_t(iox::cxx::TruncateToCapacity, name.c_str(), name.size()));
}

std::optional<RoudiWatch> joinRoudi(bool uses_iceoryx, std::string_view app_name,
                                    const std::optional<config::IceoryxConfig>& iceoryx) {
    if (!uses_iceoryx) {
        return std::nullopt;
    }
    if (iceoryx) {
        checkRoudiConfig(iceoryx->roudi_config);
    }
    initIceoryxRuntime(app_name);
    return RoudiWatch();
}

}  // namespace haptic::ipc
