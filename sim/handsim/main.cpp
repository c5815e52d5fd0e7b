// handsim: the soft real-time hand simulation. See docs/softhand.md.

#include <malloc.h>

#include <CLI/CLI.hpp>
#include <string>

#include "haptic/config/command_line.hpp"
#include "haptic/config/sim.hpp"
#include "sim_app.hpp"

int main(int argc, char** argv) {
    // Each soft-hand step builds sparse matrices of several MB. With glibc's defaults they are
    // mmap'ed and unmapped every step, and the page faults cost more than the solve (6 ms
    // instead of 14 ms of CPU per default-scene step, docs/benchmarks.md). Keep freed memory in
    // the heap instead.
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
    mallopt(M_TOP_PAD, 64 << 20);
    using haptic::config::SimConfig;
    std::string tracking_topic;
    return haptic::config::runConfiguredProgram<SimConfig>(
        argc, argv,
        {"handsim", "handsim - hand simulation publishing proxy targets and contact surfaces",
         HAPTIC_DEFAULT_CONFIG_DIR "/sim.yaml", "sim configuration file"},
        haptic::config::loadSimConfig,
        [&](CLI::App& app) {
            app.add_option("--tracking-topic", tracking_topic,
                           "track the hand from this HandPose topic instead of the scene's "
                           "tracking source (the virtual user of 'hapticemu --user' publishes on "
                           "tracking/hand)");
        },
        [&](SimConfig& config) {
            if (!tracking_topic.empty()) {
                config.scene.tracking.source = haptic::config::TrackingSource::kTopic;
                config.scene.tracking.topic = tracking_topic;
            }
        },
        haptic::handsim::runSim);
}
