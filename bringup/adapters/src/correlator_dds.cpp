#include "ugv/adapters/correlator_dds.hpp"

#include <algorithm>

#include "correlator_names.hpp"
#include "ugv/adapters/correlate_io.hpp"
#include "ugv/ipc/dds_convert.hpp"

namespace ugv::adapters {

namespace {

constexpr const char* kDroppedFix = "fix the sender; the sample was dropped and counted";

template <class T>
Result<void, Error> accepted(const T& s, const char* topic, const std::string& sender)
{
    if (const char* why = ipc::dds::check(s)) {
        return Unexpected(Error{std::string(topic) + " from '" + sender + "'", why, kDroppedFix});
    }
    return {};
}

/// The message when its numbers are within the ranges of the JSON input (bringup/correlate_io.hpp).
Result<Message, Error> plausible(Message m, const char* topic, const std::string& sender)
{
    if (auto ok = checkRanges(m); !ok) {
        return Unexpected(Error{std::string(topic) + " from '" + sender + "'", ok.error().what, kDroppedFix});
    }
    return m;
}

OoiClass toClass(std::uint8_t c)
{
    return static_cast<OoiClass>(c);
}
std::uint8_t fromClass(OoiClass c)
{
    return static_cast<std::uint8_t>(c);
}

} // namespace

Result<Message, Error> fromDds(const msg::OoiObservation& s)
{
    if (auto ok = accepted(s, "ugvsense/ooi/observations", s.ugv().to_string()); !ok) {
        return Unexpected(ok.error());
    }
    Observation m;
    m.t = s.t();
    m.ugv = s.ugv().to_string();
    m.track = s.track().to_string();
    m.cls = toClass(s.cls());
    m.ugvLat = s.ugv_lat_deg();
    m.ugvLon = s.ugv_lon_deg();
    m.ugvHeadingDeg = s.ugv_heading_deg();
    m.rangeM = s.range_m();
    m.bearingDeg = s.bearing_deg();
    return plausible(Message{m}, "ugvsense/ooi/observations", m.ugv);
}

Result<Message, Error> fromDds(const msg::UavObservation& s)
{
    if (auto ok = accepted(s, "ugvsense/ooi/uav", s.source().to_string()); !ok) {
        return Unexpected(ok.error());
    }
    UavFix m;
    m.t = s.t();
    m.cls = toClass(s.cls());
    m.lat = s.lat_deg();
    m.lon = s.lon_deg();
    return plausible(Message{m}, "ugvsense/ooi/uav", s.source().to_string());
}

Result<Message, Error> fromDds(const msg::ConfirmationState& s)
{
    if (auto ok = accepted(s, "ugvsense/ooi/confirmations", s.source().to_string()); !ok) {
        return Unexpected(ok.error());
    }
    Confirm m;
    m.t = s.t();
    m.id = s.id().to_string();
    m.state = static_cast<Confirmation>(s.state());
    return plausible(Message{m}, "ugvsense/ooi/confirmations", s.source().to_string());
}

Result<Message, Error> fromDds(const msg::PoseCorrection& s)
{
    if (auto ok = accepted(s, "ugvsense/ooi/pose_corrections", s.source().to_string()); !ok) {
        return Unexpected(ok.error());
    }
    correlator::PoseCorrection m;
    m.t = s.t();
    m.ugv = s.ugv().to_string();
    m.sinceT = s.since_t();
    m.untilT = s.until_t();
    m.dEastM = s.d_east_m();
    m.dNorthM = s.d_north_m();
    m.dHeadingDeg = s.d_heading_deg();
    return plausible(Message{m}, "ugvsense/ooi/pose_corrections", s.source().to_string());
}

void toDds(const Observation& m, std::uint64_t sequence, msg::OoiObservation& out)
{
    out.ugv(m.ugv);
    out.sequence_number(sequence);
    out.t(m.t);
    out.track(m.track);
    out.cls(fromClass(m.cls));
    out.ugv_lat_deg(m.ugvLat);
    out.ugv_lon_deg(m.ugvLon);
    out.ugv_heading_deg(m.ugvHeadingDeg);
    out.range_m(m.rangeM);
    out.bearing_deg(m.bearingDeg);
}

void toDds(const UavFix& m, const std::string& source, std::uint64_t sequence, msg::UavObservation& out)
{
    out.source(source);
    out.sequence_number(sequence);
    out.t(m.t);
    out.cls(fromClass(m.cls));
    out.lat_deg(m.lat);
    out.lon_deg(m.lon);
}

void toDds(const Confirm& m, const std::string& source, std::uint64_t sequence, msg::ConfirmationState& out)
{
    out.source(source);
    out.sequence_number(sequence);
    out.t(m.t);
    out.id(m.id);
    out.state(static_cast<std::uint8_t>(m.state));
}

void toDds(const correlator::PoseCorrection& m, const std::string& source, std::uint64_t sequence,
           msg::PoseCorrection& out)
{
    out.source(source);
    out.sequence_number(sequence);
    out.t(m.t);
    out.ugv(m.ugv);
    out.since_t(m.sinceT);
    out.until_t(m.untilT);
    out.d_east_m(m.dEastM);
    out.d_north_m(m.dNorthM);
    out.d_heading_deg(m.dHeadingDeg);
}

void toDds(const Snapshot& s, const std::string& source, std::uint64_t sequence, std::uint64_t inputsAccepted,
           std::uint64_t inputsRejected, msg::CorrelatedOoiList& out)
{
    out.source(source);
    out.sequence_number(sequence);
    out.t(s.t);
    out.inputs_accepted(inputsAccepted);
    out.inputs_rejected(inputsRejected);
    out.objects().resize(std::min<std::size_t>(s.objects.size(), msg::MAX_OBJECTS));
    for (std::size_t i = 0; i < out.objects().size(); ++i) {
        const ObjectEstimate& o = s.objects[i];
        msg::CorrelatedOoi& d = out.objects()[i];
        d.id(o.id);
        d.cls(fromClass(o.cls));
        d.lat_deg(o.lat);
        d.lon_deg(o.lon);
        d.sigma_major_m(o.sigmaMajorM);
        d.sigma_minor_m(o.sigmaMinorM);
        d.major_axis_deg(o.majorAxisDeg);
        d.state(static_cast<std::uint8_t>(o.state));
        d.observations(o.observations);
        d.ugvs().clear();
        for (std::size_t u = 0; u < o.ugvs.size() && u < 64; ++u) {
            d.ugvs().emplace_back(o.ugvs[u]);
        }
        d.zone_diameter_m(o.zoneDiameterM);
    }
    out.alerts().resize(std::min<std::size_t>(s.alerts.size(), msg::MAX_ALERTS));
    for (std::size_t i = 0; i < out.alerts().size(); ++i) {
        out.alerts()[i].non_combatant_id(s.alerts[i].nonCombatantId);
        out.alerts()[i].object_id(s.alerts[i].objectId);
        out.alerts()[i].distance_m(s.alerts[i].distanceM);
    }
}

Result<Snapshot, Error> fromDds(const msg::CorrelatedOoiList& s)
{
    if (auto ok = accepted(s, "ugvsense/ooi/correlated", s.source().to_string()); !ok) {
        return Unexpected(ok.error());
    }
    Snapshot out;
    out.t = s.t();
    for (const msg::CorrelatedOoi& o : s.objects()) {
        ObjectEstimate e;
        e.id = o.id().to_string();
        e.cls = toClass(o.cls());
        e.lat = o.lat_deg();
        e.lon = o.lon_deg();
        e.sigmaMajorM = o.sigma_major_m();
        e.sigmaMinorM = o.sigma_minor_m();
        e.majorAxisDeg = o.major_axis_deg();
        e.state = static_cast<Confirmation>(o.state());
        e.observations = o.observations();
        for (const auto& u : o.ugvs()) {
            e.ugvs.push_back(u.to_string());
        }
        e.zoneDiameterM = o.zone_diameter_m();
        out.objects.push_back(std::move(e));
    }
    for (const msg::Alert& a : s.alerts()) {
        out.alerts.push_back(Alert{a.non_combatant_id().to_string(), a.object_id().to_string(), a.distance_m()});
    }
    return out;
}

} // namespace ugv::adapters
