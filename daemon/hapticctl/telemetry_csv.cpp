#include "telemetry_csv.hpp"

#include <fmt/format.h>

namespace haptic::ctl {
namespace {
// Quotes a path for a gnuplot single-quoted string (a quote is written twice).
std::string quoted(const std::string& path) {
    std::string out = "'";
    for (const char c : path) {
        out += c;
        if (c == '\'') {
            out += '\'';
        }
    }
    return out + "'";
}
}  // namespace

std::string telemetryCsvHeader() {
    std::string header = "tick,time_s,device";
    for (std::size_t i = 0; i < msgs::kMaxActuators; ++i) {
        header += fmt::format(",command_{}", i);
    }
    return header + ",compute_us,wakeup_latency_us,read_us,write_us\n";
}

std::string telemetryCsvRow(const msgs::TelemetrySample& sample, std::int64_t origin_ns) {
    std::string row =
        fmt::format("{},{:.6f},{}", sample.tick,
                    static_cast<double>(sample.stamp_ns - origin_ns) * 1e-9, sample.device_index);
    for (const double force : sample.actuator_force_cmd) {
        row += fmt::format(",{:.4f}", force);
    }
    return row + fmt::format(",{:.2f},{:.2f},{:.2f},{:.2f}\n", sample.compute_us,
                             sample.wakeup_latency_us, sample.read_us, sample.write_us);
}

std::string telemetryPlotScript(const std::string& csv_path, const std::string& png_path) {
    // Columns: 1 tick, 2 time, 3 device, 4-7 actuator commands, 8 compute (the tick's work),
    // 9 wake-up latency, 10 read, 11 write. An actuator command is a force in N for a force
    // port (the exoskeleton) and an angle in rad for a servo (the thimble), so each device
    // gets its own panel and the label says which unit applies.
    const std::string csv = quoted(csv_path);
    std::string script = fmt::format(
        "set terminal pngcairo size 1200,1200 noenhanced\n"
        "set output {png}\n"
        "set datafile separator ','\n"
        "set multiplot layout 3,1 title {title}\n"
        "set grid\n"
        "set xlabel 'time [s]'\n",
        fmt::arg("png", quoted(png_path)),
        fmt::arg("title", quoted("hapticd telemetry: " + csv_path)));
    for (int device = 0; device < 2; ++device) {
        script += fmt::format(
            "set ylabel 'device {d} command [N force / rad servo]'\n"
            "plot {csv} every ::1 using ($3=={d} ? $2 : 1/0):4 with points pt 7 ps 0.3 title "
            "'actuator 0', "
            "{csv} every ::1 using ($3=={d} ? $2 : 1/0):5 with points pt 7 ps 0.3 title "
            "'actuator 1', "
            "{csv} every ::1 using ($3=={d} ? $2 : 1/0):6 with points pt 7 ps 0.3 title "
            "'actuator 2'\n",
            fmt::arg("d", device), fmt::arg("csv", csv));
    }
    script += fmt::format(
        "set ylabel 'loop timing [us, log scale]'\n"
        "set logscale y\n"
        "plot {csv} every ::1 using ($3==0 ? $2 : 1/0):8 with points pt 7 ps 0.3 title 'tick "
        "work (read+compute+write)', "
        "{csv} every ::1 using ($3==0 ? $2 : 1/0):10 with points pt 7 ps 0.3 title 'read', "
        "{csv} every ::1 using ($3==0 ? $2 : 1/0):11 with points pt 7 ps 0.3 title 'write', "
        "{csv} every ::1 using ($3==0 ? $2 : 1/0):9 with points pt 7 ps 0.3 title 'wake-up "
        "latency'\n"
        "unset multiplot\n",
        fmt::arg("csv", csv));
    return script;
}

}  // namespace haptic::ctl
