#pragma once

// The iceoryx side of topics.hpp: the service description of one device's channel, and the
// subscriber options for control data. hapticd, handsim, the latency probe and the test
// injector must agree on both, so they live here once.

#include <string>
#include <string_view>

#include "haptic/ipc/topics.hpp"
#include "iceoryx_posh/capro/service_description.hpp"
#include "iceoryx_posh/popo/subscriber.hpp"

namespace haptic::ipc {

// ("haptic", <device>, <event>): one channel per device and message type.
inline iox::capro::ServiceDescription deviceService(std::string_view device,
                                                    std::string_view event) {
    const std::string service(kIceoryxService);
    const std::string instance(device);
    const std::string event_name(event);
    return {iox::capro::IdString_t(iox::cxx::TruncateToCapacity, service.c_str()),
            iox::capro::IdString_t(iox::cxx::TruncateToCapacity, instance.c_str()),
            iox::capro::IdString_t(iox::cxx::TruncateToCapacity, event_name.c_str())};
}

// Control data: only the newest sample matters, so a queue of one that drops the oldest,
// and the publisher's last sample on connect.
inline iox::popo::SubscriberOptions latestValueSubscriberOptions() {
    iox::popo::SubscriberOptions options;
    options.queueCapacity = 1;
    options.historyRequest = 1;
    options.queueFullPolicy = iox::popo::QueueFullPolicy::DISCARD_OLDEST_DATA;
    return options;
}

}  // namespace haptic::ipc
