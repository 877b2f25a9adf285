// Fuzz target: one JSON line of the correlator's input (`ugvsense correlate --input`) or of its snapshots
// (`correlate-eval --snapshots`): parsed, range-checked and, when accepted, written back and parsed again.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "ugv/bringup/correlate_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const std::string_view line(reinterpret_cast<const char*>(data), size);
    if (const auto message = ugv::bringup::parseMessageLine(line); message && ugv::bringup::checkRanges(*message)) {
        (void)ugv::bringup::parseMessageLine(ugv::bringup::toJsonLine(*message));
    }
    if (const auto snapshot = ugv::bringup::parseSnapshotLine(line)) {
        (void)ugv::bringup::parseSnapshotLine(ugv::bringup::toJsonLine(*snapshot));
    }
    return 0;
}
