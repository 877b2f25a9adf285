// ugvsense record: subscribes to the service's frame ring (iceoryx `ugvsense/stereo/frames`) at low priority and
// writes a recording (hal/recording.hpp), syncing every frame so that a crash or a power cut loses at most the frame
// being written. Its queue (16 pairs) rides out write stalls; pairs it still misses are counted from the sequence
// numbers. Stops on SIGINT/SIGTERM, after --frames or --seconds.

#include <sys/resource.h>

#include <cstdint>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>

#include "ugv/adapters/calibration_file.hpp"
#include "ugv/hal/recording.hpp"
#include "ugv/ipc/iceoryx_rings.hpp"
#include "ugv/platform/clock.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"
#include "ugv/tool/stop_signal.hpp"

namespace ugv::tool {
namespace {

constexpr const char* kRecordCommand = "record";
constexpr int kQueue = 16;
constexpr int kNiceness = 10; ///< below every service task

/// The iceoryx runtime and a subscriber to the service's frames; SIGINT and SIGTERM end the recording.
Result<std::unique_ptr<ipc::FrameSubscriber>, Error> subscribe()
{
    if (auto runtime = ipc::startRuntime("ugvsense-record"); !runtime) {
        return Unexpected(runtime.error());
    }
    auto created = ipc::FrameSubscriber::create(kQueue);
    if (!created) {
        return Unexpected(created.error());
    }
    installStopHandler();
    return std::move(*created);
}

/// The recording, opened at the first frame: its size must be the calibration's (stored in the recording).
Result<hal::RecordingWriter, Error> openWriter(const Args& args, const adapters::CalibrationWithText& calibration,
                                               const FrameHeader& h)
{
    const cv::Size calibrated = calibration.calibration.imageSize;
    if (static_cast<int>(h.width) != calibrated.width || static_cast<int>(h.height) != calibrated.height) {
        return Unexpected(Error{args.get("calib"),
                                "is for " + std::to_string(calibrated.width) + "x" + std::to_string(calibrated.height) +
                                    " but the frames are " + std::to_string(h.width) + "x" + std::to_string(h.height),
                                "give the calibration of this camera at this resolution"});
    }
    hal::RecordingWriterOptions options;
    options.syncEveryFrame = !args.has("no-sync");
    options.overwrite = args.has("force");
    options.format = h.format; // the first frame's: a colour camera records colour
    auto opened = hal::RecordingWriter::create(args.get("out"), h.width, h.height, calibration.text, options);
    if (!opened) {
        return Unexpected(opened.error());
    }
    return std::move(*opened);
}

/// What the recorder wrote.
struct Tally {
    std::uint64_t written = 0;
    std::uint64_t missed = 0; ///< sequence numbers skipped: frames the recorder's queue lost
    std::uint64_t firstSequence = 0;
    std::uint64_t lastSequence = 0;
};

/// Appends a taken frame to the recording (opened at the first frame) and releases it. The exit code when the
/// recording cannot go on, else nothing.
std::optional<int> recordFrame(ipc::FrameSubscriber& subscriber, ipc::TakenFrame& frame, const Args& args,
                               const adapters::CalibrationWithText& calibration,
                               std::optional<hal::RecordingWriter>& writer, Tally& tally)
{
    const FrameHeader& h = frame.header;
    if (!writer) {
        auto opened = openWriter(args, calibration, h);
        if (!opened) {
            subscriber.release(frame);
            return reportError(kRecordCommand, opened.error());
        }
        writer.emplace(std::move(*opened));
        tally.firstSequence = h.sequence;
    } else if (h.sequence > tally.lastSequence + 1) {
        tally.missed += h.sequence - tally.lastSequence - 1;
    }
    tally.lastSequence = h.sequence;
    const auto appended = writer->append(h.sequence, h.leftStampNs, h.rightStampNs, frame.views);
    subscriber.release(frame);
    if (!appended) {
        (void)std::fprintf(stderr,
                           "ugvsense record: error: %s: cannot append: %s (%s); the %llu frames before are kept "
                           "(fix: free space on the device)\n",
                           args.get("out").c_str(), appended.error().text(), appended.error().name(),
                           static_cast<unsigned long long>(tally.written));
        return 1;
    }
    ++tally.written;
    return std::nullopt;
}

} // namespace

int runRecord(int argc, char** argv)
{
    Args args(kRecordCommand,
              "--out REC --calib FILE [--frames N] [--seconds S] [--no-sync] [--force]\n"
              "  Records the stereo pairs the running service publishes (iceoryx, zero copy) into REC with the\n"
              "  calibration FILE; syncs every frame (a crash loses at most the frame being written) unless\n"
              "  --no-sync. Needs a running RouDi and ugvsensed. Stops on Ctrl-C, after N frames or S seconds.",
              {{"out", "REC", "the recording to write", true},
               {"calib", "FILE", "the calibration of the camera being recorded (stored in the recording)", true},
               {"frames", "N", "stop after N frames", false},
               {"seconds", "S", "stop after S seconds", false},
               {"no-sync", "", "do not fdatasync each frame (faster, a power cut may lose more)", false},
               {"force", "", "overwrite an existing recording", false}});
    if (const auto exit = parseOrExit(args, argc, argv, kRecordCommand)) {
        return *exit;
    }
    const auto frames = args.number("frames", 0, 1, 1e12);
    const auto seconds = args.number("seconds", 0, 0.1, 1e9);
    for (const auto* value : {&frames, &seconds}) {
        if (!*value) {
            return reportUsageError(kRecordCommand, value->error());
        }
    }
    // Checked as the service checks it when it replays the recording.
    const auto calibration = adapters::loadCalibrationWithText(args.get("calib"));
    if (!calibration) {
        return reportError(kRecordCommand, calibration.error());
    }
    (void)::setpriority(PRIO_PROCESS, 0, kNiceness); // low priority: never in the service's way

    auto created = subscribe();
    if (!created) {
        return reportError(kRecordCommand, created.error());
    }
    const std::unique_ptr<ipc::FrameSubscriber> subscriber = std::move(*created);

    std::optional<hal::RecordingWriter> writer;
    Tally tally;
    const std::int64_t startNs = MonotonicClock::nowNs();
    const auto timeUp = [&] {
        return args.has("seconds") && static_cast<double>(MonotonicClock::nowNs() - startNs) * 1e-9 >= *seconds;
    };
    (void)std::fprintf(stderr, "ugvsense record: waiting for frames on ugvsense/stereo/frames ...\n");
    ipc::TakenFrame frame;
    while (!gStop.load() && !(args.has("frames") && static_cast<double>(tally.written) >= *frames) && !timeUp()) {
        // Oldest first: a recorder keeps every pair its queue holds.
        if (subscriber->takeOldest(frame, std::chrono::milliseconds(100)) != ipc::TakeStatus::Frame) {
            continue;
        }
        if (const auto exit = recordFrame(*subscriber, frame, args, *calibration, writer, tally)) {
            return *exit;
        }
    }
    if (!writer) {
        (void)std::fprintf(stderr, "ugvsense record: no frame arrived; nothing written (is ugvsensed running?)\n");
        return 1;
    }
    if (auto closed = writer->close(); !closed) {
        return reportError(kRecordCommand,
                           Error{args.get("out"), std::string("cannot close: ") + closed.error().text(), ""});
    }
    std::printf("recorded %llu frame(s) to %s (sequence %llu..%llu; %llu missed by the recorder)\n",
                static_cast<unsigned long long>(tally.written), args.get("out").c_str(),
                static_cast<unsigned long long>(tally.firstSequence),
                static_cast<unsigned long long>(tally.lastSequence), static_cast<unsigned long long>(tally.missed));
    return 0;
}

} // namespace ugv::tool
