#pragma once

// JSON lines of the correlator: the offline tools (`ugvsense correlate`, `correlate-sim`, `correlate-eval`) and the
// live task's logs. The input messages and the output snapshots, in the format of issue 5 (README "Correlator").
// nlohmann::json.

#include <optional>
#include <string>
#include <string_view>

#include "ugv/correlator/messages.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::bringup {

/// One input line -> a message; an error says what is wrong with the line (the caller adds the line number).
/// Rejects malformed JSON, missing or mistyped fields, NaN/inf, latitude outside [-90, 90], longitude outside
/// [-180, 180], negative range, an unknown kind, class or state.
Result<correlator::Message, Error> parseMessageLine(std::string_view line);

/// A message as one JSON line (no newline).
std::string toJsonLine(const correlator::Message& message);

/// A snapshot as one JSON line (no newline): {"t", "objects": [...], "alerts": [...]}.
std::string toJsonLine(const correlator::Snapshot& snapshot);

/// One snapshot line back (correlate-eval).
Result<correlator::Snapshot, Error> parseSnapshotLine(std::string_view line);

} // namespace ugv::bringup
