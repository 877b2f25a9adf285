#pragma once
/// The correlator's message and snapshot types under their short names, for the adapters that translate them
/// (correlate_io.cpp: JSON lines; correlator_dds.cpp: DDS samples). Private to bringup/adapters/src.

#include "ugv/correlator/messages.hpp"

namespace ugv::adapters {

using correlator::Alert;
using correlator::Confirm;
using correlator::Confirmation;
using correlator::Message;
using correlator::ObjectEstimate;
using correlator::Observation;
using correlator::OoiClass;
using correlator::Snapshot;
using correlator::UavFix;

} // namespace ugv::adapters
