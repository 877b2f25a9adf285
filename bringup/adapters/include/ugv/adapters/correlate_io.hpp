#pragma once

// JSON lines of the correlator: the offline tools (`ugvsense correlate`, `correlate-sim`, `correlate-eval`) and the
// live task's logs. The input messages and the output snapshots, in the format of issue 5 (README "Correlator").
// nlohmann::json.

#include <cstddef>
#include <istream>
#include <optional>
#include <string>
#include <string_view>

#include "ugv/correlator/messages.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::adapters {

/// Times beyond this are refused [s] (about 317 years: mission time or Unix time; at 1e17 a period no longer
/// advances a double).
inline constexpr double kMaxMessageTimeS = 1e10;
/// Observation ranges and pose corrections beyond this are refused [m].
inline constexpr double kMaxObservationRangeM = 1e5;
/// Longer input lines are refused [bytes].
inline constexpr std::size_t kMaxMessageLineBytes = 64U * 1024U;
/// Longer snapshot lines are refused [bytes] (about 300 bytes per object).
inline constexpr std::size_t kMaxSnapshotLineBytes = 64U * 1024U * 1024U;

/// One input line -> a message; an error says what is wrong with the line and names the field (the caller adds the
/// line number). Rejects a line over kMaxMessageLineBytes, malformed JSON, nesting deeper than 8, a field given twice,
/// missing or mistyped fields, NaN/inf, a time beyond +-kMaxMessageTimeS, a range outside [0, kMaxObservationRangeM],
/// an angle outside [-360, 360], a pose correction beyond kMaxObservationRangeM, latitude outside [-90, 90],
/// longitude outside [-180, 180], an unknown kind, class or state.
Result<correlator::Message, Error> parseMessageLine(std::string_view line);

/// The ranges parseMessageLine() checks, on a message from elsewhere (a DDS sample): the error names the field.
Result<void, Error> checkRanges(const correlator::Message& message);

/// Reads one line (without its newline) keeping at most maxBytes + 1 characters: the rest of a longer line is read
/// and dropped, so memory stays bounded on a hostile file and the parser still sees that the line is too long.
/// @return false at the end of the input (nothing read)
bool readBoundedLine(std::istream& in, std::string& line, std::size_t maxBytes);

/// A message as one JSON line (no newline).
std::string toJsonLine(const correlator::Message& message);

/// A snapshot as one JSON line (no newline): {"t", "objects": [...], "alerts": [...]}.
std::string toJsonLine(const correlator::Snapshot& snapshot);

/// One snapshot line back (correlate-eval): as parseMessageLine(), a line over kMaxSnapshotLineBytes, nesting deeper
/// than 8 and a field given twice are refused.
Result<correlator::Snapshot, Error> parseSnapshotLine(std::string_view line);

} // namespace ugv::adapters
