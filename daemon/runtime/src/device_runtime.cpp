#include "haptic/runtime/device_runtime.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "haptic/can/socketcan_bus.hpp"
#include "haptic/can/udp_bus.hpp"
#include "haptic/runtime/exoskeleton_channel.hpp"
#include "haptic/runtime/thimble_channel.hpp"

namespace haptic::runtime {

DeviceRuntime::DeviceRuntime(const std::vector<config::DeviceConfig>& devices,
                             const std::vector<can::CanBus*>& buses,
                             const ChannelSettings& settings) {
    if (buses.size() != devices.size()) {
        throw std::invalid_argument("DeviceRuntime: one bus per device expected");
    }
    channels_.reserve(devices.size());
    for (std::size_t i = 0; i < devices.size(); ++i) {
        if (buses[i] == nullptr) {
            throw std::invalid_argument("DeviceRuntime: no bus for device '" + devices[i].name +
                                        "'");
        }
        if (devices[i].isExoskeleton()) {
            channels_.push_back(
                std::make_unique<ExoskeletonChannel>(devices[i], *buses[i], settings));
        } else {
            channels_.push_back(std::make_unique<ThimbleChannel>(devices[i], *buses[i], settings));
        }
        auto group = std::find_if(groups_.begin(), groups_.end(),
                                  [&](const BusGroup& g) { return g.bus == buses[i]; });
        if (group == groups_.end()) {
            groups_.push_back(BusGroup{buses[i], {}, 0});
            group = groups_.end() - 1;
        }
        if (group->count == kMaxDevicesPerBus) {
            throw std::invalid_argument("DeviceRuntime: more than 8 devices on one bus");
        }
        group->members[group->count++] = channels_.back().get();
    }
}

void DeviceRuntime::attachEstopRelay(std::size_t bus_device, std::uint32_t status_id,
                                     std::int64_t timeout_ns) {
    if (bus_device >= channels_.size()) {
        throw std::invalid_argument("DeviceRuntime: the E-stop relay names no device");
    }
    estop_relay_.emplace(status_id, timeout_ns);
    estop_bus_ = &channels_[bus_device]->bus();
    char label[64];
    std::snprintf(label, sizeof(label), "0x%03x on %s's bus", status_id,
                  channels_[bus_device]->name().c_str());
    estop_label_ = label;
}

void DeviceRuntime::read(std::int64_t now_ns) noexcept {
    for (auto& group : groups_) {
        devices::EstopRelayMonitor* relay =
            group.bus == estop_bus_ && estop_relay_ ? &*estop_relay_ : nullptr;
        (void)devices::pollFrames(*group.bus, now_ns,
                                  [&group, relay](const can::CanFrame& frame, std::int64_t now) {
                                      if (relay != nullptr && relay->handleFrame(frame, now)) {
                                          return true;
                                      }
                                      for (std::size_t k = 0; k < group.count; ++k) {
                                          if (group.members[k]->handleFrame(frame, now)) {
                                              return true;
                                          }
                                      }
                                      return false;
                                  });
    }
}

void DeviceRuntime::compute(daemon::DaemonCore& core, std::int64_t now_ns) noexcept {
    if (estop_relay_) {
        daemon::HardwareEstop input = daemon::HardwareEstop::kReleased;
        switch (estop_relay_->evaluate(now_ns)) {
            case devices::EstopInput::kAwaitingFirstStatus:
                input = daemon::HardwareEstop::kAwaitingFirstStatus;
                break;
            case devices::EstopInput::kPressed:
                input = daemon::HardwareEstop::kPressed;
                break;
            case devices::EstopInput::kSilent:
                input = daemon::HardwareEstop::kSilent;
                break;
            case devices::EstopInput::kReleased:
                break;
        }
        core.setHardwareEstop(input, estop_label_);
    }
    for (std::size_t i = 0; i < channels_.size(); ++i) {
        channels_[i]->supervise(core, now_ns);
        // A device lost while RENDERING (its state stale past its heartbeat timeout, or never
        // heard since the enable) renders again only after an operator's `enable`: force
        // must not come back by itself after an outage of any length.
        if (channels_[i]->stateLost()) {
            core.requireEnable(i);
        }
    }
    for (std::size_t i = 0; i < channels_.size(); ++i) {
        channels_[i]->compute(core, i, now_ns);
        core.setDeviceReport(i, channels_[i]->report());
    }
}

void DeviceRuntime::write() noexcept {
    for (auto& channel : channels_) {
        channel->write();
    }
}

void DeviceRuntime::writeSafe() noexcept {
    for (auto& channel : channels_) {
        channel->writeSafe();
    }
}

OpenedBuses openBuses(const std::vector<config::DeviceConfig>& devices,
                      const config::EstopRelayConfig& estop_relay) {
    OpenedBuses out;
    out.per_device.resize(devices.size(), nullptr);
    out.descriptions.resize(devices.size());
    std::map<std::string, std::size_t> opened;  // bus key -> index into owned
    std::map<std::string, std::uint16_t> udp_slots;
    std::vector<std::string> bus_names;  // index into owned
    for (std::size_t i = 0; i < devices.size(); ++i) {
        const auto& can = devices[i].can;
        const bool udp = can.transport == config::CanTransport::kUdp;
        const std::string key = can.bus();
        if (udp) {
            const auto [slots, inserted] = udp_slots.emplace(key, can.udp_slots);
            if (!inserted && slots->second != can.udp_slots) {
                throw std::runtime_error(devices[i].source.string() + ": can.udp_slots " +
                                         std::to_string(can.udp_slots) + " differs from " +
                                         std::to_string(slots->second) +
                                         " of another device on UDP port " +
                                         std::to_string(can.udp_port));
            }
        }
        if (const auto found = opened.find(key); found != opened.end()) {
            out.per_device[i] = out.owned[found->second].get();
            out.descriptions[i] = bus_names[found->second] + " (shared)";
            continue;
        }
        try {
            if (udp) {
                can::UdpBusConfig config;
                config.base_port = can.udp_port;
                config.slots = can.udp_slots;
                out.owned.push_back(std::make_unique<can::UdpBus>(config));
                out.descriptions[i] = can::describe(config);
            } else {
                can::SocketCanConfig config;
                config.interface = can.interface;
                config.fd = can.fd;
                // Every device on this interface: the filter must pass all of their ids.
                for (const auto& other : devices) {
                    if (other.can.transport == config::CanTransport::kSocketCan &&
                        other.can.interface == can.interface) {
                        config.receive_ids.insert(
                            config.receive_ids.end(),
                            {other.can.state_id, other.can.heartbeat_id, other.can.fault_id});
                        config.fd = config.fd || other.can.fd;
                        if (estop_relay.enabled && other.name == estop_relay.bus_device) {
                            config.receive_ids.push_back(estop_relay.status_id);
                        }
                    }
                }
                out.owned.push_back(std::make_unique<can::SocketCanBus>(config));
                out.descriptions[i] = "SocketCAN " + can.interface;
            }
        } catch (const std::exception& error) {
            throw std::runtime_error("device '" + devices[i].name + "' (" +
                                     devices[i].source.string() +
                                     "): cannot open its CAN bus: " + error.what());
        }
        opened.emplace(key, out.owned.size() - 1);
        bus_names.push_back(out.descriptions[i]);
        out.per_device[i] = out.owned.back().get();
    }
    return out;
}

}  // namespace haptic::runtime
