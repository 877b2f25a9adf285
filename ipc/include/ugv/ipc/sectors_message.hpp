#pragma once

/// @file
/// The message the service publishes per frame to local consumers (a path planner on the same PC): the
/// obstacle sectors, the ground they were measured against and the service's health record, a fixed-size POD so that it
/// travels in a shared-memory chunk without serialisation. A receiver checks it with validate() before it trusts a
/// field: a malformed message (wrong magic or version, a sector count out of range, NaN ranges, an obstacle without a
/// finite range, unknown enum values) is an error code, never undefined behaviour downstream.
///
/// Thread-safety: plain data and pure functions. RT-safe: yes.

#include <cstddef>
#include <cstdint>

#include "ugv/platform/obstacle_sectors.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::ipc {

inline constexpr std::uint32_t kSectorsMagic = 0x53564755; ///< "UGVS" little-endian
inline constexpr std::uint16_t kSectorsVersion = 2;        ///< 2: the ground estimate after the sectors

/// State of the camera as the capture task sees it. LeftOnly: the left camera streams alone (a one-camera rig, or
/// the pair's right camera lost and being retried): the sectors come from the one-camera detector, degraded.
enum class CameraState : std::uint8_t { Streaming = 0, Reconnecting = 1, Stopped = 2, LeftOnly = 3 };

/// Counters since the service started and the state of the last frame.
struct HealthRecord {
    std::uint64_t framesCaptured = 0;  ///< pairs delivered by the camera
    std::uint64_t framesProcessed = 0; ///< pairs that produced sectors (full or degraded)
    std::uint64_t framesDropped = 0;   ///< pairs never processed (overload: latest frame wins) + camera gaps
    std::uint64_t cameraGaps = 0;      ///< frames the camera's sequence numbers say were lost before capture
    std::uint64_t deadlineMisses = 0;  ///< frames whose sectors came later than the deadline
    std::uint64_t degradedFrames = 0;  ///< frames published from the ground-plane-only path
    std::uint64_t cameraReconnects = 0;
    std::int64_t lastLatencyNs = 0; ///< [ns] capture stamp to publish of this message
    CameraState camera = CameraState::Streaming;
    std::uint8_t reserved[7] = {};
};

struct SectorsMessage {
    std::uint32_t magic = kSectorsMagic;
    std::uint16_t version = kSectorsVersion;
    std::uint16_t reserved = 0;
    std::int64_t publishStampNs = 0; ///< [ns] CLOCK_MONOTONIC when published
    ObstacleSectors sectors;
    GroundSummary ground; ///< the plane the sectors were measured against
    HealthRecord health;
};

enum class MessageError : std::uint8_t { TooShort, BadMagic, BadVersion, BadCount, BadSector, BadGround, BadHealth };

/// Human-readable text of the error (static string).
const char* toString(MessageError error) noexcept;

/// Checks `message` spanning `availableBytes`: magic, version, 0 < count <= kMaxSectors, every sector in use
/// with known enum values, finite bearings (min < max), confidence in [0, 1], Obstacle with a finite positive
/// range and a kind, Clear with range +inf, a ground with finite angles within +-90 deg and a finite height >= 0,
/// and a known camera state.
Result<void, MessageError> validate(const SectorsMessage& message, std::size_t availableBytes) noexcept;

} // namespace ugv::ipc
