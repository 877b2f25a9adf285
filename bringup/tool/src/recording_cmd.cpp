// ugvsense recording: look into, import and export recordings (hal/recording.hpp).
// - info REC: geometry, frame count, sequence gaps, duration and rate, corrupt frames, a cut-off tail and whether the
//   stored calibration is usable (exit 1 when not).
// - import --pairs DIR --calib FILE --out REC [--timestamps CSV] [--fps F] [--colour]: PNG pairs (left*/right*) to a
//   recording, grey or (--colour) BGR.
// - export REC --out DIR: frame_NNNNNN_left.png / _right.png, frames.csv (frame, sequence, stamps) and
//   calibration.yaml.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "ugv/adapters/calibration_file.hpp"
#include "ugv/hal/recording.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/commands.hpp"
#include "ugv/tool/detection.hpp"
#include "ugv/tool/pair_files.hpp"

namespace ugv::tool {
namespace {

constexpr const char* kRecordingCommand = "recording";

int runInfo(const Args& args)
{
    if (args.positional().size() != 2) {
        return reportUsageError(kRecordingCommand, Error{"ugvsense recording info", "give one recording",
                                                         "ugvsense recording info REC.ugvrec"});
    }
    const std::string path = args.positional()[1];
    auto reader = hal::RecordingReader::open(path);
    if (!reader) {
        return reportError(kRecordingCommand, reader.error());
    }
    auto scan = hal::scanRecording(path);
    if (!scan) {
        return reportError(kRecordingCommand, scan.error());
    }
    const double seconds = static_cast<double>(scan->lastStampNs - scan->firstStampNs) * 1e-9;
    std::printf("recording %s: %ux%u %s stereo, calibration %zu bytes\n", path.c_str(), reader->info().width,
                reader->info().height, reader->info().format == PixelFormat::Bgr8 ? "colour (BGR)" : "grey",
                reader->info().calibrationText.size());
    std::printf("frames: %llu complete (sequence %llu..%llu, %llu missing in gaps), %.3f s",
                static_cast<unsigned long long>(scan->frames), static_cast<unsigned long long>(scan->firstSequence),
                static_cast<unsigned long long>(scan->lastSequence),
                static_cast<unsigned long long>(scan->sequenceGaps), seconds);
    if (scan->frames > 1 && seconds > 0.0) {
        std::printf(", %.2f fps", static_cast<double>(scan->frames - 1) / seconds);
    }
    std::printf("\n");
    if (scan->corruptFrames > 0) {
        std::printf("corrupt: %llu frame(s) failed their CRC or had a damaged prefix and were skipped\n",
                    static_cast<unsigned long long>(scan->corruptFrames));
    }
    if (scan->trailingBytes > 0) {
        std::printf("truncated: the last %llu bytes are a frame cut off while it was written (a crash or power "
                    "cut); the %llu complete frames before it are recovered\n",
                    static_cast<unsigned long long>(scan->trailingBytes),
                    static_cast<unsigned long long>(scan->frames));
    }
    // As the service reads it when it replays the recording.
    const auto calibration =
        adapters::parseCalibration(reader->info().calibrationText, path + " (its stored calibration)");
    if (!calibration) {
        std::printf("calibration: unusable: %s\n", calibration.error().message().c_str());
        return 1;
    }
    const cv::Size frames(static_cast<int>(reader->info().width), static_cast<int>(reader->info().height));
    if (calibration->imageSize != frames) {
        std::printf("calibration: for %dx%d, not the frames' size: the service would refuse to replay it\n",
                    calibration->imageSize.width, calibration->imageSize.height);
        return 1;
    }
    std::printf("calibration: OK (%s form, baseline %.3f m%s)\n", calibration->rectified ? "rectified" : "full",
                calibration->baselineM(), calibration->mount ? ", with a mount" : ", no mount");
    return 0;
}

/// Reads `frame,stamp_ns` lines (a header line is allowed) into frame index -> stamp.
Result<std::map<std::size_t, std::int64_t>, Error> readTimestamps(const std::string& path)
{
    std::ifstream in(path);
    if (!in) {
        return Unexpected(Error{path, "cannot open the timestamps file", "give a CSV of frame,stamp_ns lines"});
    }
    std::map<std::size_t, std::int64_t> stamps;
    std::string line;
    int lineNo = 0;
    while (std::getline(in, line)) {
        ++lineNo;
        if (line.empty() || line[0] == '#' || (lineNo == 1 && line.find_first_not_of("0123456789,- ") != line.npos)) {
            continue; // comment, blank or header
        }
        std::istringstream fields(line);
        std::int64_t frame = -1;
        std::int64_t stamp = 0;
        char comma = 0;
        if (!(fields >> frame >> comma >> stamp) || comma != ',' || frame < 0) {
            return Unexpected(Error{path + ":" + std::to_string(lineNo),
                                    "expected 'frame,stamp_ns', got '" + line + "'",
                                    "one line per pair: its index in name order, a comma, the time in ns"});
        }
        stamps[static_cast<std::size_t>(frame)] = stamp;
    }
    return stamps;
}

/// An image of a pair as the recording stores it: BGR with --colour, else grey.
cv::Mat readForRecording(const std::filesystem::path& path, bool colour)
{
    return colour ? readImage(path, cv::IMREAD_COLOR) : readGrey(path);
}

/// Appends the pairs to the recording, stamped from `stamps` (by index) or else at `fps`; a pair that is
/// unreadable or not of `size` is skipped with a warning. The number skipped.
Result<std::size_t, Error> appendPairs(hal::RecordingWriter& writer, const std::vector<PairFiles>& pairs, cv::Size size,
                                       const std::map<std::size_t, std::int64_t>& stamps, const Args& args, double fps)
{
    const bool colour = args.has("colour");
    std::size_t skipped = 0;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
        const PairFiles& pair = pairs[k];
        const cv::Mat left = readForRecording(pair.left, colour);
        const cv::Mat right = readForRecording(pair.right, colour);
        if (left.empty() || right.empty() || left.size() != size || right.size() != size) {
            std::cerr << "ugvsense recording: warning: skipped " << pair.name
                      << ": unreadable, or not the size of the first pair (" << size.width << "x" << size.height
                      << ")\n";
            ++skipped;
            continue;
        }
        const auto it = stamps.find(k);
        if (!stamps.empty() && it == stamps.end()) {
            return Unexpected(Error{args.get("timestamps"),
                                    "no timestamp for pair " + std::to_string(k) + " (" + pair.name + ")",
                                    "give one line per pair, or leave out --timestamps to use --fps"});
        }
        const std::int64_t stamp = it != stamps.end()
                                       ? it->second
                                       : static_cast<std::int64_t>(std::llround(static_cast<double>(k) / fps * 1e9));
        const StereoViews images =
            colour ? bgrViews(bgrViewOf(left), bgrViewOf(right)) : greyViews(viewOf(left), viewOf(right));
        if (auto appended = writer.append(k, stamp, stamp, images); !appended) {
            return Unexpected(Error{args.get("out"), std::string("cannot append: ") + appended.error().text(),
                                    "check the free space"});
        }
    }
    return skipped;
}

int runImport(const Args& args)
{
    for (const char* needed : {"pairs", "calib", "out"}) {
        if (!args.has(needed)) {
            return reportUsageError(kRecordingCommand,
                                    Error{"ugvsense recording import", std::string("--") + needed + " is required",
                                          "ugvsense recording import --pairs DIR --calib FILE --out REC"});
        }
    }
    const auto fps = args.number("fps", 10.0, 0.1, 1000.0);
    if (!fps) {
        return reportUsageError(kRecordingCommand, fps.error());
    }
    auto listing = listPairs(args.get("pairs"));
    if (!listing) {
        return reportError(kRecordingCommand, listing.error());
    }
    if (listing->pairs.empty()) {
        return reportError(kRecordingCommand, Error{args.get("pairs"), "no left*/right* image pairs found",
                                                    "name the images left<rest>.png and right<rest>.png"});
    }
    for (const std::string& lonely : listing->unpaired) {
        std::cerr << "ugvsense recording: warning: skipped " << lonely << '\n';
    }
    if (std::any_of(listing->pairs.begin(), listing->pairs.end(),
                    [](const PairFiles& p) { return isJpeg(p.left) || isJpeg(p.right); })) {
        std::cerr << "ugvsense recording: warning: " << kJpegPairsWarning << '\n';
    }
    // Checked as the service will check it when it replays the recording (a deep or absurd file is refused here).
    const auto loaded = adapters::loadCalibrationWithText(args.get("calib"));
    if (!loaded) {
        return reportError(kRecordingCommand, loaded.error());
    }
    const vision::StereoCalibration* calib = &loaded->calibration;
    std::map<std::size_t, std::int64_t> stamps;
    if (args.has("timestamps")) {
        auto read = readTimestamps(args.get("timestamps"));
        if (!read) {
            return reportError(kRecordingCommand, read.error());
        }
        stamps = std::move(*read);
    }

    const cv::Mat first = readGrey(listing->pairs.front().left);
    if (first.empty()) {
        return reportError(kRecordingCommand,
                           Error{listing->pairs.front().left.string(), "not a readable image", "check the file"});
    }
    if (first.size() != calib->imageSize) {
        return reportError(kRecordingCommand,
                           Error{listing->pairs.front().left.string(),
                                 "image size " + std::to_string(first.cols) + "x" + std::to_string(first.rows) +
                                     " differs from " + args.get("calib") + "'s " +
                                     std::to_string(calib->imageSize.width) + "x" +
                                     std::to_string(calib->imageSize.height),
                                 "give the calibration of these cameras at this resolution"});
    }
    hal::RecordingWriterOptions options;
    options.overwrite = args.has("force");
    options.syncEveryFrame = false; // an import can be redone: one sync at close
    options.format = args.has("colour") ? PixelFormat::Bgr8 : PixelFormat::Grey8;
    auto writer = hal::RecordingWriter::create(args.get("out"), static_cast<std::uint32_t>(first.cols),
                                               static_cast<std::uint32_t>(first.rows), loaded->text, options);
    if (!writer) {
        return reportError(kRecordingCommand, writer.error());
    }
    const auto skipped = appendPairs(*writer, listing->pairs, first.size(), stamps, args, *fps);
    if (!skipped) {
        return reportError(kRecordingCommand, skipped.error());
    }
    if (auto closed = writer->close(); !closed) {
        return reportError(kRecordingCommand,
                           Error{args.get("out"), std::string("cannot close: ") + closed.error().text(), ""});
    }
    std::printf("imported %llu pair(s) of %zu (%zu skipped) into %s (%dx%d)\n",
                static_cast<unsigned long long>(writer->framesWritten()), listing->pairs.size(), *skipped,
                args.get("out").c_str(), first.cols, first.rows);
    return 0;
}

int runExport(const Args& args)
{
    if (args.positional().size() != 2 || !args.has("out")) {
        return reportUsageError(kRecordingCommand,
                                Error{"ugvsense recording export", "give one recording and --out DIR",
                                      "ugvsense recording export REC.ugvrec --out DIR"});
    }
    const std::string path = args.positional()[1];
    auto reader = hal::RecordingReader::open(path);
    if (!reader) {
        return reportError(kRecordingCommand, reader.error());
    }
    const std::filesystem::path out = args.get("out");
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (ec) {
        return reportError(kRecordingCommand,
                           Error{out.string(), "cannot create the folder: " + ec.message(), "choose a writable place"});
    }
    std::ofstream(out / "calibration.yaml", std::ios::binary) << reader->info().calibrationText;
    std::ofstream index(out / "frames.csv");
    index << "frame,sequence,left_stamp_ns,right_stamp_ns\n";
    const auto only = args.number("frame", -1, 0, 1e12);
    if (!only) {
        return reportUsageError(kRecordingCommand, only.error());
    }
    std::size_t k = 0;
    std::size_t written = 0;
    hal::ReadStatus status = hal::ReadStatus::Frame;
    while ((status = reader->next()) == hal::ReadStatus::Frame) {
        if (*only >= 0 && static_cast<double>(k) != *only) {
            ++k;
            continue;
        }
        ++written;
        const StereoViews v = reader->views();
        char stem[32];
        (void)std::snprintf(stem, sizeof(stem), "frame_%06zu", k);
        for (const bool right : {false, true}) {
            const cv::Mat m = matOver(v, right); // grey or colour, as recorded
            if (m.empty()) {
                continue; // a left-only frame: its right camera was lost when it was recorded
            }
            const char* side = right ? "right" : "left";
            const auto file = out / (std::string(stem) + "_" + side + ".png");
            if (!cv::imwrite(file.string(), m)) {
                return reportError(kRecordingCommand, Error{file.string(), "cannot write PNG", "check the free space"});
            }
        }
        const FrameHeader& h = reader->header();
        index << k << ',' << h.sequence << ',' << h.leftStampNs << ',' << h.rightStampNs << '\n';
        ++k;
    }
    if (status == hal::ReadStatus::IoError) {
        return reportError(kRecordingCommand,
                           Error{path, std::string("read failed: ") + reader->lastError().text(), "check the device"});
    }
    std::printf("exported %zu frame(s) of %s to %s (frame_NNNNNN_{left,right}.png, frames.csv, calibration.yaml)\n",
                written, path.c_str(), out.string().c_str());
    if (reader->corruptFrames() > 0) {
        std::printf("skipped %llu corrupt frame(s)\n", static_cast<unsigned long long>(reader->corruptFrames()));
    }
    if (status == hal::ReadStatus::Truncated) {
        std::printf("the recording ends in a cut-off frame (%llu bytes): every complete frame was exported\n",
                    static_cast<unsigned long long>(reader->trailingBytes()));
    }
    return 0;
}

} // namespace

int runRecording(int argc, char** argv)
{
    Args args(
        kRecordingCommand,
        "info REC | import --pairs DIR --calib FILE --out REC [--timestamps CSV] [--fps F] [--colour] [--force] | "
        "export REC --out DIR [--frame N]\n"
        "  info: frame count, sequence gaps, duration, corrupt frames and a cut-off tail (what a crash left)\n"
        "  import: left*/right* image pairs (name order) into a recording; stamps from --timestamps\n"
        "    (frame,stamp_ns lines, frame = index in name order) or every 1/fps s\n"
        "  export: frame_NNNNNN_{left,right}.png, frames.csv and calibration.yaml",
        {{"pairs", "DIR", "import: folder of left*/right* image pairs", false},
         {"calib", "FILE", "import: calibration file stored in the recording", false},
         {"out", "REC|DIR", "import: the recording to write; export: the folder", false},
         {"timestamps", "CSV", "import: frame,stamp_ns per pair", false},
         {"fps", "F", "import: frame rate when there are no timestamps, default 10", false},
         {"colour", "", "import: record the pairs in colour (BGR: for the one-camera detector)", false},
         {"force", "", "import: overwrite an existing recording", false},
         {"frame", "N", "export: only frame N (0-based, in file order)", false}});
    if (const auto exit = parseOrExit(args, argc, argv, kRecordingCommand, Positionals::Allowed)) {
        return *exit;
    }
    const std::string action = args.positional().empty() ? std::string() : args.positional()[0];
    if (action == "info") {
        return runInfo(args);
    }
    if (action == "import") {
        return runImport(args);
    }
    if (action == "export") {
        return runExport(args);
    }
    return reportUsageError(kRecordingCommand,
                            Error{"ugvsense recording", "expected info, import or export, got '" + action + "'",
                                  "see 'ugvsense recording --help'"});
}

} // namespace ugv::tool
