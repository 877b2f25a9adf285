#pragma once

/// @file
/// The correlator's messages (correlator/messages.hpp) <-> their DDS samples (ipc/idl/ugvsense.idl): the same
/// fields as the JSON lines of `ugvsense correlate`. A received sample becomes a message only after
/// ipc::dds::check() accepted it; the error then names the topic, the sender and what is wrong.
///
/// Thread-safety: pure functions. RT-safe: no.

#include <cstdint>
#include <string>

#include "ugv/correlator/messages.hpp"
#include "ugv/ipc/dds_bus.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::adapters {

namespace msg = ipc::dds::msg;

Result<correlator::Message, Error> fromDds(const msg::OoiObservation& s);
Result<correlator::Message, Error> fromDds(const msg::UavObservation& s);
Result<correlator::Message, Error> fromDds(const msg::ConfirmationState& s);
Result<correlator::Message, Error> fromDds(const msg::PoseCorrection& s);

/// A message as the sample of its topic (`source` names the sender of UAV fixes, confirmations and corrections;
/// an observation's sender is its ugv). `sequence` numbers the sender's samples from 1.
void toDds(const correlator::Observation& m, std::uint64_t sequence, msg::OoiObservation& out);
void toDds(const correlator::UavFix& m, const std::string& source, std::uint64_t sequence, msg::UavObservation& out);
void toDds(const correlator::Confirm& m, const std::string& source, std::uint64_t sequence,
           msg::ConfirmationState& out);
void toDds(const correlator::PoseCorrection& m, const std::string& source, std::uint64_t sequence,
           msg::PoseCorrection& out);

/// A snapshot as the correlated list (objects beyond MAX_OBJECTS and alerts beyond MAX_ALERTS are cut off; the
/// counts tell).
void toDds(const correlator::Snapshot& s, const std::string& source, std::uint64_t sequence,
           std::uint64_t inputsAccepted, std::uint64_t inputsRejected, msg::CorrelatedOoiList& out);
/// Back (listen, correlate --from-dds, tests).
Result<correlator::Snapshot, Error> fromDds(const msg::CorrelatedOoiList& s);

} // namespace ugv::adapters
