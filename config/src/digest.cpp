#include <openssl/evp.h>

#include <array>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>

#include "haptic/config/daemon.hpp"
#include "haptic/config/error.hpp"

namespace haptic::config {

namespace {

using DigestContext = std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)>;

void addFile(EVP_MD_CTX* context, const std::filesystem::path& path) {
    // A directory opens as a stream and reads as nothing; a vanished file does not open.
    // Either must fail here rather than digest as an empty file.
    if (!std::filesystem::is_regular_file(path)) {
        throw ConfigError(path.string(), 0, 0, "", "cannot be read for the configuration digest");
    }
    std::ifstream file(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(file)),
                            std::istreambuf_iterator<char>());
    if (!file.good() && !file.eof()) {
        throw ConfigError(path.string(), 0, 0, "", "cannot be read for the configuration digest");
    }
    // Each file's length first: moving bytes from one file to the next changes the digest.
    const std::string length = std::to_string(bytes.size()) + ":";
    if (EVP_DigestUpdate(context, length.data(), length.size()) != 1 ||
        EVP_DigestUpdate(context, bytes.data(), bytes.size()) != 1) {
        throw ConfigError(path.string(), 0, 0, "", "SHA-256 failed on this file");
    }
}

}  // namespace

std::string configurationDigest(const DaemonConfig& config) {
    const DigestContext context(EVP_MD_CTX_new(), &EVP_MD_CTX_free);
    if (!context || EVP_DigestInit_ex(context.get(), EVP_sha256(), nullptr) != 1) {
        throw ConfigError(config.source.string(), 0, 0, "", "SHA-256 is not available");
    }
    addFile(context.get(), config.source);
    if (!config.dds.profiles_file.empty()) {
        addFile(context.get(), config.dds.profiles_file);
    }
    for (const DeviceConfig& device : config.devices) {
        addFile(context.get(), device.source);
    }
    std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
    unsigned int size = 0;
    if (EVP_DigestFinal_ex(context.get(), digest.data(), &size) != 1) {
        throw ConfigError(config.source.string(), 0, 0, "", "SHA-256 failed");
    }
    static constexpr char kHex[] = "0123456789abcdef";
    std::string text = "sha256:";
    for (unsigned int i = 0; i < size; ++i) {
        text += kHex[digest[i] >> 4];
        text += kHex[digest[i] & 0xF];
    }
    return text;
}

}  // namespace haptic::config
