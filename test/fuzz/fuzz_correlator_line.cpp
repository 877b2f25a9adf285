// Fuzz target: one JSON line of the correlator's input (`ugvsense correlate --input`) or of its snapshots
// (`correlate-eval --snapshots`): parsed, range-checked and, when accepted, written back and parsed again.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "ugv/adapters/correlate_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const std::string_view line(reinterpret_cast<const char*>(data), size);
    if (const auto message = ugv::adapters::parseMessageLine(line); message && ugv::adapters::checkRanges(*message)) {
        (void)ugv::adapters::parseMessageLine(ugv::adapters::toJsonLine(*message));
    }
    if (const auto snapshot = ugv::adapters::parseSnapshotLine(line)) {
        (void)ugv::adapters::parseSnapshotLine(ugv::adapters::toJsonLine(*snapshot));
    }
    return 0;
}
