#include "ugv/service/report.hpp"

#include <charconv>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace ugv::service {

namespace {

double us(std::chrono::nanoseconds d)
{
    return static_cast<double>(d.count()) / 1000.0;
}

std::string histogramJson(const rt::LatencyHistogram& h)
{
    char text[256];
    (void)std::snprintf(text, sizeof(text),
                        "{\"count\": %llu, \"p50_us\": %.1f, \"p90_us\": %.1f, \"p99_us\": %.1f, \"p999_us\": %.1f, "
                        "\"max_us\": %.1f}",
                        static_cast<unsigned long long>(h.count()), us(h.p50()), us(h.p90()), us(h.p99()), us(h.p999()),
                        us(h.count() > 0 ? h.max() : std::chrono::nanoseconds(0)));
    return text;
}

std::string histogramLine(const char* name, const rt::LatencyHistogram& h)
{
    char text[256];
    (void)std::snprintf(
        text, sizeof(text), "  %-10s p50 %9.1f  p90 %9.1f  p99 %9.1f  p99.9 %9.1f  max %9.1f us  (%llu)\n", name,
        us(h.p50()), us(h.p90()), us(h.p99()), us(h.p999()), us(h.count() > 0 ? h.max() : std::chrono::nanoseconds(0)),
        static_cast<unsigned long long>(h.count()));
    return text;
}

} // namespace

int processThreadCount()
{
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("Threads:", 0) == 0) {
            const std::size_t first = line.find_first_not_of(" \t", 8);
            int count = 0;
            if (first != std::string::npos) {
                (void)std::from_chars(line.data() + first, line.data() + line.size(), count); // 0 when unreadable
            }
            return count;
        }
    }
    return 0;
}

std::string formatReport(const ServiceReport& r, const ReportExtras& extras)
{
    std::ostringstream out;
    char line[512];
    (void)std::snprintf(
        line, sizeof(line),
        "frames: %llu published of %llu captured in %.2f s; deadline %.1f ms: %llu missed; dropped %llu "
        "(camera gaps %llu); degraded %llu (left camera alone %llu); bad %llu; loan failures %llu; camera "
        "reconnects %llu\n",
        static_cast<unsigned long long>(r.framesPublished), static_cast<unsigned long long>(r.framesCaptured),
        r.wallSeconds, us(r.deadline) / 1000.0, static_cast<unsigned long long>(r.deadlineMisses),
        static_cast<unsigned long long>(r.framesDropped), static_cast<unsigned long long>(r.cameraGaps),
        static_cast<unsigned long long>(r.degradedFrames), static_cast<unsigned long long>(r.leftOnlyFrames),
        static_cast<unsigned long long>(r.badFrames), static_cast<unsigned long long>(r.loanFailures),
        static_cast<unsigned long long>(r.cameraReconnects));
    out << line << "latency (after warm-up):\n";
    for (int s = 0; s < kStageCount; ++s) {
        out << histogramLine(stageName(static_cast<Stage>(s)), r.stages[static_cast<std::size_t>(s)]);
    }
    out << "detect by stage (full-pipeline frames):\n";
    for (int s = 0; s < vision::kVisionStageCount; ++s) {
        const rt::LatencyHistogram& h = r.detectStages[static_cast<std::size_t>(s)];
        if (h.count() > 0 && h.max().count() > 0) { // stages the matcher mode does not run stay 0
            out << "  " << histogramLine(vision::stageName(static_cast<vision::VisionStage>(s)), h);
        }
    }
    out << "cpu:";
    for (const TaskCpu& c : r.cpu) {
        (void)std::snprintf(line, sizeof(line), " %s %.2f s (%.0f %%)", c.name, c.cpuSeconds,
                            r.wallSeconds > 0.0 ? 100.0 * c.cpuSeconds / r.wallSeconds : 0.0);
        out << line;
    }
    out << "\n";
    if (extras.allocationsAfterWarmup) {
        out << "allocations after warm-up (capture + vision + publish threads): " << *extras.allocationsAfterWarmup
            << "\n";
    }
    out << "threads at start: " << extras.threadCount << "; memory locked: "
        << (extras.lockedBytes ? std::to_string(*extras.lockedBytes / 1024) + " KiB" : std::string("unknown")) << "\n";
    out << "tasks:\n" << r.threads;
    return out.str();
}

std::string reportJson(const ServiceReport& r, const ReportExtras& extras)
{
    std::ostringstream out;
    out << "{\n  \"frames\": " << r.framesPublished << ",\n  \"frames_captured\": " << r.framesCaptured
        << ",\n  \"deadline_us\": " << us(r.deadline) << ",\n  \"deadline_misses\": " << r.deadlineMisses
        << ",\n  \"drops\": " << r.framesDropped << ",\n  \"camera_gaps\": " << r.cameraGaps
        << ",\n  \"degraded\": " << r.degradedFrames << ",\n  \"left_only\": " << r.leftOnlyFrames
        << ",\n  \"bad_frames\": " << r.badFrames << ",\n  \"allocations_after_warmup\": "
        << (extras.allocationsAfterWarmup ? std::to_string(*extras.allocationsAfterWarmup) : std::string("null"))
        << ",\n  \"wall_s\": " << r.wallSeconds << ",\n  \"threads\": " << extras.threadCount
        << ",\n  \"locked_bytes\": " << (extras.lockedBytes ? std::to_string(*extras.lockedBytes) : std::string("null"))
        << ",\n  \"end_to_end\": " << histogramJson(r.stages[static_cast<std::size_t>(Stage::EndToEnd)])
        << ",\n  \"stages\": {";
    for (int s = 0; s < kStageCount - 1; ++s) {
        out << (s > 0 ? ",\n" : "\n") << "    \"" << stageName(static_cast<Stage>(s))
            << "\": " << histogramJson(r.stages[static_cast<std::size_t>(s)]);
    }
    out << "\n  },\n  \"detect_stages\": {";
    for (int s = 0; s < vision::kVisionStageCount; ++s) {
        out << (s > 0 ? ",\n" : "\n") << "    \"" << vision::stageName(static_cast<vision::VisionStage>(s))
            << "\": " << histogramJson(r.detectStages[static_cast<std::size_t>(s)]);
    }
    out << "\n  },\n  \"cpu\": {";
    for (std::size_t i = 0; i < r.cpu.size(); ++i) {
        char text[160];
        (void)std::snprintf(text, sizeof(text), "%s\n    \"%s\": {\"seconds\": %.3f, \"percent\": %.1f}",
                            i > 0 ? "," : "", r.cpu[i].name, r.cpu[i].cpuSeconds,
                            r.wallSeconds > 0.0 ? 100.0 * r.cpu[i].cpuSeconds / r.wallSeconds : 0.0);
        out << text;
    }
    out << "\n  }\n}\n";
    return out.str();
}

} // namespace ugv::service
