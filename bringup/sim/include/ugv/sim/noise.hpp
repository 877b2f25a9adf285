#pragma once

/// @file
/// Internal: hashed value noise and band-limited fBm in world coordinates for the procedural textures.
/// A texture is a pure function of the world point, so both cameras see the same pattern. Octaves shorter
/// than the pixel footprint fade out to their mean (mip-like prefiltering), which removes aliasing at
/// distance together with the jittered supersampling.
///
/// Thread-safety: pure functions. RT-safe: yes.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>

namespace ugv::sim::detail {

struct Octave {
    double wavelengthM = 1.0; ///< [m]
    double amplitude = 0.0;
};

inline std::uint32_t hash3(std::int64_t x, std::int64_t y, std::int64_t z, std::uint32_t seed) noexcept
{
    auto h = static_cast<std::uint32_t>(seed * 0x9E3779B1U);
    h ^= static_cast<std::uint32_t>(x) * 0x85EBCA77U;
    h = (h << 13U) | (h >> 19U);
    h ^= static_cast<std::uint32_t>(y) * 0xC2B2AE3DU;
    h = (h << 13U) | (h >> 19U);
    h ^= static_cast<std::uint32_t>(z) * 0x27D4EB2FU;
    h ^= h >> 15U;
    h *= 0x2C1B3C6DU;
    h ^= h >> 12U;
    h *= 0x297A2D39U;
    h ^= h >> 15U;
    return h;
}

/// Uniform in [0, 1) at an integer lattice point.
inline double lattice(std::int64_t x, std::int64_t y, std::int64_t z, std::uint32_t seed) noexcept
{
    constexpr double kScale = 1.0 / 4294967296.0;
    return static_cast<double>(hash3(x, y, z, seed)) * kScale;
}

inline double smooth(double t) noexcept
{
    return t * t * (3.0 - 2.0 * t);
}

/// 2-D value noise in [0, 1) with smoothstep interpolation; lattice spacing 1.
inline double valueNoise2(double x, double y, std::uint32_t seed) noexcept
{
    const double fx = std::floor(x);
    const double fy = std::floor(y);
    const auto ix = static_cast<std::int64_t>(fx);
    const auto iy = static_cast<std::int64_t>(fy);
    const double tx = smooth(x - fx);
    const double ty = smooth(y - fy);
    const double a = lattice(ix, iy, 0, seed);
    const double b = lattice(ix + 1, iy, 0, seed);
    const double c = lattice(ix, iy + 1, 0, seed);
    const double d = lattice(ix + 1, iy + 1, 0, seed);
    return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}

/// 3-D value noise in [0, 1); lattice spacing 1.
inline double valueNoise3(double x, double y, double z, std::uint32_t seed) noexcept
{
    const double fx = std::floor(x);
    const double fy = std::floor(y);
    const double fz = std::floor(z);
    const auto ix = static_cast<std::int64_t>(fx);
    const auto iy = static_cast<std::int64_t>(fy);
    const auto iz = static_cast<std::int64_t>(fz);
    const double tx = smooth(x - fx);
    const double ty = smooth(y - fy);
    const double tz = smooth(z - fz);
    double plane[2] = {0.0, 0.0};
    for (int k = 0; k < 2; ++k) {
        const double a = lattice(ix, iy, iz + k, seed);
        const double b = lattice(ix + 1, iy, iz + k, seed);
        const double c = lattice(ix, iy + 1, iz + k, seed);
        const double d = lattice(ix + 1, iy + 1, iz + k, seed);
        const double ab = a + (b - a) * tx;
        plane[k] = ab + ((c + (d - c) * tx) - ab) * ty;
    }
    return plane[0] + (plane[1] - plane[0]) * tz;
}

/// Weight of an octave of wavelength `wavelengthM` for a pixel footprint `footprintM`: 1 when the octave
/// spans at least 2 footprints, 0 below 1 footprint (then it contributes its mean).
inline double octaveWeight(double wavelengthM, double footprintM) noexcept
{
    return std::clamp(wavelengthM / footprintM - 1.0, 0.0, 1.0);
}

/// Zero-mean fBm: sum of amplitude * (noise(wavelength, seed) - 0.5) over the octaves, band-limited to the
/// footprint; each octave has its own seed (seed + 1, seed + 2, ...).
template <class Noise>
inline double fbm(std::span<const Octave> octaves, double footprintM, std::uint32_t seed, Noise noise) noexcept
{
    double sum = 0.0;
    std::uint32_t octaveSeed = seed;
    for (const Octave& o : octaves) {
        ++octaveSeed;
        const double w = octaveWeight(o.wavelengthM, footprintM);
        if (w > 0.0) {
            sum += w * o.amplitude * (noise(o.wavelengthM, octaveSeed) - 0.5);
        }
    }
    return sum;
}

/// Zero-mean 2-D fBm, band-limited to the footprint.
inline double fbm2(double x, double y, std::span<const Octave> octaves, double footprintM, std::uint32_t seed) noexcept
{
    return fbm(octaves, footprintM, seed, [&](double wavelengthM, std::uint32_t octaveSeed) {
        return valueNoise2(x / wavelengthM, y / wavelengthM, octaveSeed);
    });
}

/// Zero-mean 3-D fBm, band-limited to the footprint.
inline double fbm3(double x, double y, double z, std::span<const Octave> octaves, double footprintM,
                   std::uint32_t seed) noexcept
{
    return fbm(octaves, footprintM, seed, [&](double wavelengthM, std::uint32_t octaveSeed) {
        const double s = 1.0 / wavelengthM;
        return valueNoise3(x * s, y * s, z * s, octaveSeed);
    });
}

} // namespace ugv::sim::detail
