#include "ugv/adapters/correlate_io.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "correlator_names.hpp"

namespace ugv::adapters {

using correlator::PoseCorrection;
using correlator::toString;

namespace {

using nlohmann::json;

Error lineError(const std::string& what, const std::string& fix = "")
{
    return Error{"", what, fix};
}

/// Physically plausible ranges of the numeric fields (latitude and longitude are checked by latLon()). Beyond them the
/// correlator's arithmetic fails: a range of 1e308 m gives NaN positions, a time of 1e17 s no longer advances by a
/// period, a sigma of 1e19 m breaks the map.
struct FieldRange {
    const char* key;
    double min;
    double max;
    const char* unit;
    const char* fix;
};
constexpr const char* kTimeFix = "mission time in seconds; Unix time fits too";
constexpr const char* kAngleFix = "degrees, e.g. 0..360 or -180..180";
constexpr std::array kRanges{
    FieldRange{"t", -kMaxMessageTimeS, kMaxMessageTimeS, "s", kTimeFix},
    FieldRange{"since_t", -kMaxMessageTimeS, kMaxMessageTimeS, "s", kTimeFix},
    FieldRange{"until_t", -kMaxMessageTimeS, kMaxMessageTimeS, "s", kTimeFix},
    FieldRange{"range_m", 0.0, kMaxObservationRangeM, "m", "a sensor's range to the object in metres"},
    FieldRange{"bearing_deg", -360.0, 360.0, "deg", kAngleFix},
    FieldRange{"ugv_heading_deg", -360.0, 360.0, "deg", kAngleFix},
    FieldRange{"d_heading_deg", -360.0, 360.0, "deg", kAngleFix},
    FieldRange{"d_east_m", -kMaxObservationRangeM, kMaxObservationRangeM, "m", "a pose correction in metres"},
    FieldRange{"d_north_m", -kMaxObservationRangeM, kMaxObservationRangeM, "m", "a pose correction in metres"},
};

/// A finite value within the field's range (kRanges; other fields: finite only).
Result<void, Error> fieldInRange(const char* key, double v)
{
    if (!std::isfinite(v)) {
        return Unexpected(lineError(std::string("field '") + key + "' is not finite"));
    }
    for (const FieldRange& r : kRanges) {
        if (std::string_view(key) == r.key && (v < r.min || v > r.max)) {
            std::ostringstream what;
            what << "field '" << key << "' value " << v << " is outside [" << r.min << ", " << r.max << "] " << r.unit;
            return Unexpected(lineError(what.str(), r.fix));
        }
    }
    return {};
}

/// Nesting depth and duplicate keys, seen while parsing (nlohmann::json keeps the last of duplicate keys silently).
class ParseChecks {
public:
    bool operator()(int depth, json::parse_event_t event, json& parsed)
    {
        if (depth > kMaxJsonDepth && !error_) {
            error_ = lineError("nested deeper than " + std::to_string(kMaxJsonDepth) + " levels",
                               "one flat JSON object per line");
        }
        if (event == json::parse_event_t::object_start) {
            keys_.emplace_back();
        } else if (event == json::parse_event_t::object_end && !keys_.empty()) {
            keys_.pop_back();
        } else if (event == json::parse_event_t::key && !keys_.empty() && parsed.is_string() &&
                   !keys_.back().insert(parsed.get<std::string>()).second && !error_) {
            error_ = lineError("field '" + parsed.get<std::string>() + "' is given twice", "keep one of them");
        }
        return true;
    }
    [[nodiscard]] const std::optional<Error>& error() const { return error_; }

private:
    static constexpr int kMaxJsonDepth = 8;
    std::vector<std::set<std::string>> keys_;
    std::optional<Error> error_;
};

/// The number `key` of `j`: present, a number, finite, within its plausible range (kRanges).
Result<double, Error> number(const json& j, const char* key)
{
    const auto it = j.find(key);
    if (it == j.end()) {
        return Unexpected(lineError(std::string("missing field '") + key + "'"));
    }
    if (!it->is_number()) {
        return Unexpected(lineError(std::string("field '") + key + "' is not a number"));
    }
    const double v = it->get<double>();
    if (auto ok = fieldInRange(key, v); !ok) {
        return Unexpected(ok.error());
    }
    return v;
}

Result<std::string, Error> text(const json& j, const char* key)
{
    const auto it = j.find(key);
    if (it == j.end()) {
        return Unexpected(lineError(std::string("missing field '") + key + "'"));
    }
    if (!it->is_string() || it->get_ref<const std::string&>().empty()) {
        return Unexpected(lineError(std::string("field '") + key + "' is not a non-empty string"));
    }
    return it->get<std::string>();
}

/// The one of `values` whose name (toString, the output's spelling) is `s`: names are written once.
template <class E, std::size_t N>
std::optional<E> byName(const std::string& s, const std::array<E, N>& values)
{
    for (const E v : values) {
        if (s == toString(v)) {
            return v;
        }
    }
    return std::nullopt;
}

Result<OoiClass, Error> ooiClass(const std::string& s)
{
    constexpr std::array kClasses{OoiClass::Static, OoiClass::Mobile, OoiClass::NonCombatant, OoiClass::Unknown};
    if (const auto c = byName(s, kClasses)) {
        return *c;
    }
    return Unexpected(lineError("unknown class '" + s + "'", "use static, mobile, noncombatant or unknown"));
}

Result<Confirmation, Error> confirmation(const std::string& s)
{
    constexpr std::array kStates{Confirmation::Unknown, Confirmation::ConfirmedPositive,
                                 Confirmation::ConfirmedNegative};
    if (const auto c = byName(s, kStates)) {
        return *c;
    }
    return Unexpected(lineError("unknown state '" + s + "'", "use unknown, confirmed_positive or confirmed_negative"));
}

Result<void, Error> latLon(double lat, double lon, const char* what)
{
    if (lat < -90.0 || lat > 90.0) {
        return Unexpected(lineError(std::string(what) + " latitude " + std::to_string(lat) + " is outside -90..90"));
    }
    if (lon < -180.0 || lon > 180.0) {
        return Unexpected(lineError(std::string(what) + " longitude " + std::to_string(lon) + " is outside -180..180"));
    }
    return {};
}

/// A JSON object of at most `maxBytes`, nested at most 8 deep, no key given twice.
Result<json, Error> parseObjectLine(std::string_view line, std::size_t maxBytes, const char* fix)
{
    if (line.size() > maxBytes) {
        return Unexpected(lineError("line over " + std::to_string(maxBytes) + " bytes", fix));
    }
    ParseChecks checks;
    json j = json::parse(
        line, [&checks](int depth, json::parse_event_t event, json& parsed) { return checks(depth, event, parsed); },
        false);
    if (j.is_discarded()) {
        return Unexpected(lineError("not valid JSON", fix));
    }
    if (checks.error()) {
        return Unexpected(*checks.error());
    }
    if (!j.is_object()) {
        return Unexpected(lineError("not a JSON object", fix));
    }
    return j;
}

/// Collects the first error of several field reads.
class Fields {
public:
    explicit Fields(const json& j) : j_(j) {}
    double num(const char* key)
    {
        auto v = number(j_, key);
        if (!v) {
            keep(v.error());
            return 0.0;
        }
        return *v;
    }
    /// A count: a whole number in 0..INT_MAX (a JSON number beyond it is refused, not wrapped or undefined).
    int count(const char* key)
    {
        const double v = num(key);
        if (!(v >= 0.0 && v <= static_cast<double>(std::numeric_limits<int>::max()) && v == std::floor(v))) {
            keep(lineError(std::string("'") + key + "' is " + std::to_string(v) + ", not a count 0.." +
                           std::to_string(std::numeric_limits<int>::max())));
            return 0;
        }
        return static_cast<int>(v);
    }
    std::string str(const char* key)
    {
        auto v = text(j_, key);
        if (!v) {
            keep(v.error());
            return {};
        }
        return *v;
    }
    /// `text` as an object class or a confirmation state; a bad one is kept as the error.
    OoiClass classOf(const std::string& text) { return kept(ooiClass(text), OoiClass::Static); }
    Confirmation stateOf(const std::string& text) { return kept(confirmation(text), Confirmation::Unknown); }
    /// Keeps the error of a position outside the globe's ranges.
    void checkLatLon(double lat, double lon, const char* what)
    {
        if (auto ok = latLon(lat, lon, what); !ok) {
            keep(ok.error());
        }
    }
    void keep(Error e)
    {
        if (!error_) {
            error_ = std::move(e);
        }
    }
    [[nodiscard]] const std::optional<Error>& error() const { return error_; }
    /// `m` as a message, or the first error of the reads and checks.
    template <class M>
    Result<Message, Error> message(M m) const
    {
        if (error_) {
            return Unexpected(*error_);
        }
        return Message{std::move(m)};
    }

private:
    template <class T>
    T kept(Result<T, Error> v, T fallback)
    {
        if (!v) {
            keep(v.error());
            return fallback;
        }
        return *v;
    }

    const json& j_;
    std::optional<Error> error_;
};

Result<Message, Error> observation(const json& j)
{
    Fields f(j);
    Observation o;
    o.t = f.num("t");
    o.ugv = f.str("ugv");
    o.track = f.str("track");
    const std::string cls = f.str("class");
    o.ugvLat = f.num("ugv_lat");
    o.ugvLon = f.num("ugv_lon");
    o.ugvHeadingDeg = f.num("ugv_heading_deg");
    o.rangeM = f.num("range_m");
    o.bearingDeg = f.num("bearing_deg");
    o.cls = f.classOf(cls);
    f.checkLatLon(o.ugvLat, o.ugvLon, "ugv");
    return f.message(o);
}

Result<Message, Error> uav(const json& j)
{
    Fields f(j);
    UavFix u;
    u.t = f.num("t");
    const std::string cls = f.str("class");
    u.lat = f.num("lat");
    u.lon = f.num("lon");
    u.cls = f.classOf(cls);
    f.checkLatLon(u.lat, u.lon, "uav");
    return f.message(u);
}

Result<Message, Error> confirm(const json& j)
{
    Fields f(j);
    Confirm c;
    c.t = f.num("t");
    c.id = f.str("id");
    c.state = f.stateOf(f.str("state"));
    return f.message(c);
}

Result<Message, Error> poseCorrection(const json& j)
{
    Fields f(j);
    PoseCorrection p;
    p.t = f.num("t");
    p.ugv = f.str("ugv");
    p.sinceT = f.num("since_t");
    p.untilT = f.num("until_t");
    p.dEastM = f.num("d_east_m");
    p.dNorthM = f.num("d_north_m");
    p.dHeadingDeg = f.num("d_heading_deg");
    if (p.untilT < p.sinceT) {
        f.keep(lineError("until_t is before since_t"));
    }
    return f.message(p);
}

json objectJson(const ObjectEstimate& o)
{
    return json{{"id", o.id},
                {"class", toString(o.cls)},
                {"lat", o.lat},
                {"lon", o.lon},
                {"sigma_major_m", o.sigmaMajorM},
                {"sigma_minor_m", o.sigmaMinorM},
                {"major_axis_deg", o.majorAxisDeg},
                {"state", toString(o.state)},
                {"observations", o.observations},
                {"ugvs", o.ugvs},
                {"zone_diameter_m", o.zoneDiameterM}};
}

} // namespace

bool readBoundedLine(std::istream& in, std::string& line, std::size_t maxBytes)
{
    line.clear();
    std::streambuf* buffer = in.rdbuf();
    bool any = false;
    for (int c = buffer->sbumpc(); c != std::char_traits<char>::eof(); c = buffer->sbumpc()) {
        any = true;
        if (c == '\n') {
            return true;
        }
        if (line.size() <= maxBytes) {
            line.push_back(static_cast<char>(c));
        }
    }
    in.setstate(std::ios::eofbit);
    return any;
}

Result<void, Error> checkRanges(const Message& message)
{
    std::vector<std::pair<const char*, double>> fields;
    if (const auto* o = std::get_if<Observation>(&message)) {
        fields = {
            {"t", o->t}, {"range_m", o->rangeM}, {"bearing_deg", o->bearingDeg}, {"ugv_heading_deg", o->ugvHeadingDeg}};
    } else if (const auto* p = std::get_if<PoseCorrection>(&message)) {
        fields = {{"t", p->t},
                  {"since_t", p->sinceT},
                  {"until_t", p->untilT},
                  {"d_east_m", p->dEastM},
                  {"d_north_m", p->dNorthM},
                  {"d_heading_deg", p->dHeadingDeg}};
    } else {
        fields = {{"t", std::visit([](const auto& m) { return m.t; }, message)}};
    }
    for (const auto& [key, value] : fields) {
        if (auto ok = fieldInRange(key, value); !ok) {
            return ok;
        }
    }
    return {};
}

Result<Message, Error> parseMessageLine(std::string_view line)
{
    const auto parsed = parseObjectLine(line, kMaxMessageLineBytes, "one JSON object per line");
    if (!parsed) {
        return Unexpected(parsed.error());
    }
    const json& j = *parsed;
    auto kind = text(j, "kind");
    if (!kind) {
        return Unexpected(kind.error());
    }
    if (*kind == "observation") {
        return observation(j);
    }
    if (*kind == "uav") {
        return uav(j);
    }
    if (*kind == "confirm") {
        return confirm(j);
    }
    if (*kind == "pose_correction") {
        return poseCorrection(j);
    }
    return Unexpected(lineError("unknown kind '" + *kind + "'", "use observation, uav, confirm or pose_correction"));
}

std::string toJsonLine(const Message& message)
{
    json j;
    if (const auto* o = std::get_if<Observation>(&message)) {
        j = json{{"t", o->t},
                 {"kind", "observation"},
                 {"ugv", o->ugv},
                 {"track", o->track},
                 {"class", toString(o->cls)},
                 {"ugv_lat", o->ugvLat},
                 {"ugv_lon", o->ugvLon},
                 {"ugv_heading_deg", o->ugvHeadingDeg},
                 {"range_m", o->rangeM},
                 {"bearing_deg", o->bearingDeg}};
    } else if (const auto* u = std::get_if<UavFix>(&message)) {
        j = json{{"t", u->t}, {"kind", "uav"}, {"class", toString(u->cls)}, {"lat", u->lat}, {"lon", u->lon}};
    } else if (const auto* c = std::get_if<Confirm>(&message)) {
        j = json{{"t", c->t}, {"kind", "confirm"}, {"id", c->id}, {"state", toString(c->state)}};
    } else if (const auto* p = std::get_if<PoseCorrection>(&message)) {
        j = json{{"t", p->t},
                 {"kind", "pose_correction"},
                 {"ugv", p->ugv},
                 {"since_t", p->sinceT},
                 {"until_t", p->untilT},
                 {"d_east_m", p->dEastM},
                 {"d_north_m", p->dNorthM},
                 {"d_heading_deg", p->dHeadingDeg}};
    }
    return j.dump();
}

std::string toJsonLine(const Snapshot& snapshot)
{
    json objects = json::array();
    for (const ObjectEstimate& o : snapshot.objects) {
        objects.push_back(objectJson(o));
    }
    json alerts = json::array();
    for (const Alert& a : snapshot.alerts) {
        alerts.push_back(json{{"noncombatant", a.nonCombatantId}, {"object", a.objectId}, {"distance_m", a.distanceM}});
    }
    return json{{"t", snapshot.t}, {"objects", objects}, {"alerts", alerts}}.dump();
}

Result<Snapshot, Error> parseSnapshotLine(std::string_view line)
{
    const auto parsed =
        parseObjectLine(line, kMaxSnapshotLineBytes, "one snapshot per line, as `ugvsense correlate` writes");
    if (!parsed) {
        return Unexpected(parsed.error());
    }
    const json& j = *parsed;
    auto t = number(j, "t");
    if (!t) {
        return Unexpected(t.error());
    }
    const auto objects = j.find("objects");
    if (objects == j.end() || !objects->is_array()) {
        return Unexpected(lineError("missing array 'objects'"));
    }
    Snapshot s;
    s.t = *t;
    for (const json& o : *objects) {
        if (!o.is_object()) {
            return Unexpected(lineError("an entry of 'objects' is not an object"));
        }
        Fields f(o);
        ObjectEstimate e;
        e.id = f.str("id");
        const std::string cls = f.str("class");
        e.lat = f.num("lat");
        e.lon = f.num("lon");
        e.sigmaMajorM = f.num("sigma_major_m");
        e.sigmaMinorM = f.num("sigma_minor_m");
        e.majorAxisDeg = f.num("major_axis_deg");
        const std::string state = f.str("state");
        e.observations = f.count("observations");
        e.zoneDiameterM = f.num("zone_diameter_m");
        if (f.error()) {
            return Unexpected(*f.error());
        }
        auto c = ooiClass(cls);
        auto st = confirmation(state);
        if (!c || !st) {
            return Unexpected(!c ? c.error() : st.error());
        }
        e.cls = *c;
        e.state = *st;
        if (const auto u = o.find("ugvs"); u != o.end() && u->is_array()) {
            for (const json& name : *u) {
                if (name.is_string()) {
                    e.ugvs.push_back(name.get<std::string>());
                }
            }
        }
        s.objects.push_back(std::move(e));
    }
    if (const auto alerts = j.find("alerts"); alerts != j.end() && alerts->is_array()) {
        for (const json& a : *alerts) {
            Fields f(a);
            Alert alert{f.str("noncombatant"), f.str("object"), f.num("distance_m")};
            if (!f.error()) {
                s.alerts.push_back(std::move(alert));
            }
        }
    }
    return s;
}

} // namespace ugv::adapters
