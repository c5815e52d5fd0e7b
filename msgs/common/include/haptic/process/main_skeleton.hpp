#pragma once

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <string_view>

namespace haptic::process {

// An error whose one-line report names what kind of mistake it is, e.g. "configuration error"
// for a bad YAML file, so the operator knows where to look before reading the message.
class LabelledError : public std::runtime_error {
  public:
    LabelledError(const char* label, const std::string& message)
        : std::runtime_error(message), label_(label) {}
    [[nodiscard]] const char* label() const noexcept { return label_; }

  private:
    const char* label_;
};

// The shared skeleton of every executable's main(): after the command line is parsed, `body`
// runs the program and returns its exit status. An exception that escapes it becomes one line
// on stderr, "<program>: [<label>: ]<message>", and exit status 1, so no executable ends with
// std::terminate's abort and core dump on a bad file or a missing broker.
template <class Body>
int runMain(std::string_view program, Body&& body) noexcept {
    const std::string name(program);
    try {
        return body();
    } catch (const LabelledError& error) {
        std::fprintf(stderr, "%s: %s: %s\n", name.c_str(), error.label(), error.what());
    } catch (const std::exception& error) {
        std::fprintf(stderr, "%s: %s\n", name.c_str(), error.what());
    }
    return EXIT_FAILURE;
}

}  // namespace haptic::process
