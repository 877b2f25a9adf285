#include "ugv/platform/sectors_json.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ugv {

const char* stateName(SectorState state) noexcept
{
    switch (state) {
    case SectorState::Clear:
        return "clear";
    case SectorState::Obstacle:
        return "obstacle";
    case SectorState::Unknown:
        break;
    }
    return "unknown";
}

const char* kindName(ObstacleKind kind) noexcept
{
    switch (kind) {
    case ObstacleKind::Positive:
        return "positive";
    case ObstacleKind::Negative:
        return "negative";
    case ObstacleKind::None:
        break;
    }
    return "none";
}

const char* className(DangerClass danger) noexcept
{
    switch (danger) {
    case DangerClass::Green:
        return "green";
    case DangerClass::Blue:
        return "blue";
    case DangerClass::Red:
        return "red";
    case DangerClass::Unknown:
        break;
    }
    return "unknown";
}

std::string jsonString(const std::string& text)
{
    std::string out = "\"";
    for (const char c : text) {
        switch (c) {
        case '"':
            out += "\\\"";
            break;
        case '\\':
            out += "\\\\";
            break;
        case '\n':
            out += "\\n";
            break;
        case '\r':
            out += "\\r";
            break;
        case '\t':
            out += "\\t";
            break;
        default:
            if (static_cast<unsigned char>(c) < 0x20) {
                char escaped[8];
                (void)std::snprintf(escaped, sizeof(escaped), "\\u%04x", static_cast<unsigned>(c));
                out += escaped;
            } else {
                out += c;
            }
        }
    }
    return out + "\"";
}

std::string jsonNumber(double value)
{
    if (!std::isfinite(value)) {
        return "null";
    }
    char text[32];
    (void)std::snprintf(text, sizeof(text), "%.6g", value);
    return text;
}

std::string sectorsJsonArray(const ObstacleSectors& sectors, int indent)
{
    const std::string pad(static_cast<std::size_t>(std::max(indent, 0)), ' ');
    std::string out = "[";
    for (int i = 0; i < sectors.count; ++i) {
        const Sector& s = sectors.sectors[static_cast<std::size_t>(i)];
        out += (i == 0 ? "\n" : ",\n") + pad + "{\"bearing_min_deg\": " + jsonNumber(s.bearingMinDeg) +
               ", \"bearing_max_deg\": " + jsonNumber(s.bearingMaxDeg) + ", \"range_m\": " + jsonNumber(s.rangeM) +
               ", \"kind\": \"" + kindName(s.kind) + "\", \"state\": \"" + stateName(s.state) + "\", \"class\": \"" +
               className(s.danger) + "\", \"height_m\": " + jsonNumber(s.heightM) +
               ", \"confidence\": " + jsonNumber(s.confidence) + "}";
    }
    return out + (sectors.count > 0 ? "\n" + pad.substr(std::min<std::size_t>(pad.size(), 2)) + "]" : "]");
}

} // namespace ugv
