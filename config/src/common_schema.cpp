#include <algorithm>
#include <cstdio>
#include <iterator>
#include <memory>
#include <regex>
#include <set>
#include <string>
#include <utility>

#include "schema.hpp"

namespace haptic::config::detail {
namespace {

namespace fs = std::filesystem;

// Participant profile names declared in a Fast DDS XML file. A plain scan rather than an
// XML parser: this only has to catch a misspelt name before Fast DDS fails obscurely at
// participant creation; Fast DDS itself validates the file.
std::set<std::string> participantProfiles(const fs::path& xml_file) {
    std::set<std::string> names;
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> handle(std::fopen(xml_file.c_str(), "rb"),
                                                           &std::fclose);
    if (!handle) {
        return names;
    }
    std::string content;
    char buffer[4096];
    std::size_t n = 0;
    while ((n = std::fread(buffer, 1, sizeof(buffer), handle.get())) > 0) {
        content.append(buffer, n);
    }
    static const std::regex kParticipant(
        R"re(<participant\s[^>]*profile_name\s*=\s*["']([^"']*)["'])re");
    for (auto it = std::sregex_iterator(content.begin(), content.end(), kParticipant);
         it != std::sregex_iterator(); ++it) {
        names.insert((*it)[1].str());
    }
    return names;
}

std::string hex(std::uint32_t id) {
    char buffer[16];
    std::snprintf(buffer, sizeof(buffer), "0x%03x", id);
    return buffer;
}

}  // namespace

LogLevel readLogLevel(MapReader& root) {
    return root.optional("log_level", LogLevel::kInfo, spec::Enum<LogLevel>{});
}

SimLinkConfig readSimLink(MapReader& root) {
    MapReader map = root.requiredMap("sim_link");
    SimLinkConfig out;
    out.transport = map.required("transport", spec::Enum<SimTransport>{});
    map.finish();
    return out;
}

DdsConfig readDds(MapReader& root) {
    MapReader map = root.requiredMap("dds");
    DdsConfig out;
    out.domain_id = map.optional("domain_id", 0, spec::Integer<int>::closed(0, 232));
    out.profiles_file = map.required("profiles_file", spec::File{});
    auto [profile, field] = map.requiredWithField("participant_profile", spec::Text{});
    const std::set<std::string> declared = participantProfiles(out.profiles_file);
    if (!declared.contains(profile)) {
        std::string names;
        for (const auto& name : declared) {
            names += (names.empty() ? "" : ", ") + name;
        }
        field.fail("a <participant profile_name> declared in " + out.profiles_file.string() +
                   " (declared: " + (names.empty() ? std::string("none") : names) + ")");
    }
    out.participant_profile = std::move(profile);
    map.finish();
    return out;
}

std::optional<IceoryxConfig> readIceoryx(MapReader& root) {
    std::optional<MapReader> map = root.optionalMap("iceoryx");
    if (!map) {
        return std::nullopt;
    }
    IceoryxConfig out;
    out.roudi_config = map->required("roudi_config", spec::File{});
    map->finish();
    return out;
}

Pose readPose(MapReader map) {
    Pose out;
    out.position_m = map.required(
        "position_m", spec::Reals<3>{spec::Real::closed(-kMaxPositionM, kMaxPositionM)});
    out.rpy_rad = degToRad(
        map.optional("rpy_deg", Vec3{}, spec::Reals<3>{spec::Real::closed(-360.0, 360.0)}));
    map.finish();
    return out;
}

Transform readTransform(MapReader map) {
    Transform out;
    out.translation_m = map.required(
        "translation_m", spec::Reals<3>{spec::Real::closed(-kMaxPositionM, kMaxPositionM)});
    out.rpy_rad =
        degToRad(map.required("rpy_deg", spec::Reals<3>{spec::Real::closed(-360.0, 360.0)}));
    map.finish();
    return out;
}

void checkDeviceBindings(const SceneConfig& scene, const std::vector<DeviceConfig>& devices,
                         const ListReader& device_list) {
    for (std::size_t i = 0; i < devices.size(); ++i) {
        const DeviceConfig& device = devices[i];
        const Field entry = device_list.at(i);
        if (!scene.devices.contains(device.name)) {
            std::string bound;
            for (const auto& [name, binding] : scene.devices) {
                bound += (bound.empty() ? "" : ", ") + name;
            }
            entry.fail("a device bound in scene '" + scene.name +
                           "' (bound: " + (bound.empty() ? std::string("none") : bound) + ")",
                       "'" + device.name + "'");
        }
        if (device.isExoskeleton() && scene.hand.model == HandModel::kFingertip) {
            entry.fail("a device the scene's hand model can drive",
                       "exoskeleton '" + device.name + "' with hand.model fingertip (no joints)");
        }
    }
}

ListReader requiredDeviceList(MapReader& root) {
    return root.requiredList("devices", 1, kMaxDevices, "a path to a device file");
}

std::vector<DeviceConfig> readDeviceList(const ListReader& list,
                                         std::optional<int> control_rate_hz) {
    std::vector<DeviceConfig> devices;
    for (std::size_t i = 0; i < list.size(); ++i) {
        const Field entry = list.at(i);
        const fs::path path = entry.as(spec::File{});
        DeviceConfig device = readDevice(MapReader::openFile(path), path, control_rate_hz);

        for (std::size_t j = 0; j < devices.size(); ++j) {
            const DeviceConfig& other = devices[j];
            const std::string where = "devices[" + std::to_string(j) + "]";
            if (other.name == device.name) {
                entry.fail("a device with a unique name",
                           "another device named '" + device.name + "' (" + where + ")");
            }
            // UDP blocks [udp_port, udp_port + udp_slots) that overlap are one bus in all but
            // name: their parties hear each other on the shared ports.
            const auto& a = device.can;
            const auto& b = other.can;
            if (a.transport == CanTransport::kUdp && b.transport == CanTransport::kUdp &&
                a.udp_port != b.udp_port && a.udp_port < b.udp_port + b.udp_slots &&
                b.udp_port < a.udp_port + a.udp_slots) {
                entry.fail("a device whose UDP port block does not overlap that of '" + other.name +
                               "' (" + where + ", ports " + std::to_string(b.udp_port) + "-" +
                               std::to_string(b.udp_port + b.udp_slots - 1) + ")",
                           "'" + device.name + "' on ports " + std::to_string(a.udp_port) + "-" +
                               std::to_string(a.udp_port + a.udp_slots - 1));
            }
            // Two devices on one bus answering the same id would corrupt each other's state.
            if (other.can.bus() != device.can.bus()) {
                continue;
            }
            const std::uint32_t mine[] = {device.can.command_id, device.can.state_id,
                                          device.can.heartbeat_id, device.can.fault_id};
            const std::uint32_t theirs[] = {other.can.command_id, other.can.state_id,
                                            other.can.heartbeat_id, other.can.fault_id};
            for (const std::uint32_t id : mine) {
                if (std::find(std::begin(theirs), std::end(theirs), id) != std::end(theirs)) {
                    entry.fail("a device whose CAN ids on " + device.can.bus() +
                                   " differ from those of '" + other.name + "' (" + where + ")",
                               "'" + device.name + "' also using " + hex(id));
                }
            }
        }
        devices.push_back(std::move(device));
    }
    return devices;
}

}  // namespace haptic::config::detail
