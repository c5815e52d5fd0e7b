#pragma once

// hapticctl's bash completion, generated from its CLI11 definition (`hapticctl
// --bash-completion`; installed to share/bash-completion/completions/hapticctl), so it never
// drifts from the options the program takes.

#include <map>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace haptic::ctl {

// `positional_words`: per subcommand, the words its positional argument takes (method names);
// a subcommand with a file argument (a positional without listed words) completes file names.
[[nodiscard]] std::string bashCompletion(
    const CLI::App& app, const std::map<std::string, std::vector<std::string>>& positional_words);

}  // namespace haptic::ctl
