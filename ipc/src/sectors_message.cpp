#include "ugv/ipc/sectors_message.hpp"

#include <cmath>

namespace ugv::ipc {

const char* toString(MessageError error) noexcept
{
    switch (error) {
    case MessageError::TooShort:
        return "message shorter than a SectorsMessage";
    case MessageError::BadMagic:
        return "not a sectors message (bad magic)";
    case MessageError::BadVersion:
        return "unsupported sectors message version";
    case MessageError::BadCount:
        return "sector count out of range";
    case MessageError::BadSector:
        return "a sector has invalid fields (enum, bearing, range or confidence)";
    case MessageError::BadGround:
        return "the ground estimate has a non-finite or impossible angle or height";
    case MessageError::BadHealth:
        return "the health record has an unknown camera state";
    }
    return "unknown message error";
}

namespace {

bool validSector(const Sector& s) noexcept
{
    if (!std::isfinite(s.bearingMinDeg) || !std::isfinite(s.bearingMaxDeg) || !(s.bearingMinDeg < s.bearingMaxDeg)) {
        return false;
    }
    if (!(s.confidence >= 0.0F && s.confidence <= 1.0F) || std::isnan(s.heightM) || std::isnan(s.rangeM)) {
        return false;
    }
    const auto state = static_cast<std::uint8_t>(s.state);
    const auto kind = static_cast<std::uint8_t>(s.kind);
    const auto danger = static_cast<std::uint8_t>(s.danger);
    if (state > static_cast<std::uint8_t>(SectorState::Obstacle) ||
        kind > static_cast<std::uint8_t>(ObstacleKind::Negative) ||
        danger > static_cast<std::uint8_t>(DangerClass::Red)) {
        return false;
    }
    switch (s.state) {
    case SectorState::Obstacle:
        return std::isfinite(s.rangeM) && s.rangeM > 0.0F && s.kind != ObstacleKind::None &&
               s.danger != DangerClass::Unknown;
    case SectorState::Clear:
        return std::isinf(s.rangeM) && s.rangeM > 0.0F && s.danger == DangerClass::Green;
    case SectorState::Unknown:
        return s.danger == DangerClass::Unknown;
    }
    return false;
}

} // namespace

Result<void, MessageError> validate(const SectorsMessage& message, std::size_t availableBytes) noexcept
{
    if (availableBytes < sizeof(SectorsMessage)) {
        return Unexpected(MessageError::TooShort);
    }
    if (message.magic != kSectorsMagic) {
        return Unexpected(MessageError::BadMagic);
    }
    if (message.version != kSectorsVersion) {
        return Unexpected(MessageError::BadVersion);
    }
    const ObstacleSectors& sectors = message.sectors;
    if (sectors.count <= 0 || sectors.count > kMaxSectors) {
        return Unexpected(MessageError::BadCount);
    }
    for (int i = 0; i < sectors.count; ++i) {
        if (!validSector(sectors.sectors[static_cast<std::size_t>(i)])) {
            return Unexpected(MessageError::BadSector);
        }
    }
    const GroundSummary& g = message.ground;
    const auto angle = [](float deg) { return std::isfinite(deg) && std::abs(deg) <= 90.0F; };
    if (!angle(g.pitchDeg) || !angle(g.rollDeg) || !std::isfinite(g.cameraHeightM) || g.cameraHeightM < 0.0F) {
        return Unexpected(MessageError::BadGround);
    }
    if (static_cast<std::uint8_t>(message.health.camera) > static_cast<std::uint8_t>(CameraState::LeftOnly)) {
        return Unexpected(MessageError::BadHealth);
    }
    return {};
}

} // namespace ugv::ipc
