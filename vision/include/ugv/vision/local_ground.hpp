#pragma once

/// @file
/// The real ground's height above the frame's ground plane, per sector along the range (SectorBuilder's local
/// ground).
///
/// A plane is the ground of a test track, not of a street: a cambered road falls off to both sides of its crown
/// (within a sector, whose lateral offset grows with the range, that is a height linear in the range), a grade
/// change bends the profile, a verge or a pavement sits a few centimetres higher. Against one plane these read as
/// obstacles or drops, whatever the threshold. So the heights are measured from a profile learnt from the frame:
///  - per sector and range bin (binM), a histogram of the heights above the plane (1 cm bins, as far from the plane
///    as the profile may go there, plus bandM); the mode within +-bandM of a height is where the ground is: a face
///    (a box, a kerb, a trench's far wall) spreads its pixels over many heights, the ground piles them up at one;
///  - per sector, from the vehicle outwards, the surface connected to the nearest ground seen: a bin whose mode near
///    the extrapolation (from at least minPoints pixels, median-filtered over three bins so that a feature one bin
///    deep, like a trench's far wall, is not taken for the ground's course) follows it within stepM plus maxSlope
///    over one bin moves the profile (level and a slope, at most maxSlope); a bin that jumps is not ground (a kerb,
///    a pavement, a face, a drop) and the last ground level holds. So a smooth surface (camber, grade) is followed
///    and a step is not.
///  - the profile stays within +-(maxOffsetM + maxSlope r) of the plane when the walk starts on it (a grade that
///    goes on is followed as far as the detector looks: 4 % from 8 m is 0.48 m up at 20 m), within +-maxOffsetM
///    when it starts on a raised or sunken surface (a pavement where the road is out of view).
///
/// Thread-safety: thread-bound. RT-safe: everything but configure() (which allocates).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace ugv::vision {

struct LocalGroundConfig {
    float bandM = 0.25F;      ///< [m] a bin's mode is looked for within +- this of the profile's extrapolation
    float binM = 1.0F;        ///< [m] range bins
    int minPoints = 10;       ///< pixels a bin needs to give a mode
    float stepM = 0.03F;      ///< [m] a bin within this of the extrapolation (plus maxSlope over a bin) follows it
    float maxSlope = 0.04F;   ///< [m/m] the profile's slope against the plane (4 %: camber, grade changes)
    float maxOffsetM = 0.20F; ///< [m] the profile stays within +- this of the plane at the vehicle (plus maxSlope r)
};

class LocalGround {
public:
    /// Allocates for `sectors` x ceil(maxRangeM / binM) range bins, each with the height bins of its band.
    void configure(const LocalGroundConfig& config, int sectors, float maxRangeM);
    /// Forgets the last frame.
    void clear() noexcept;
    /// One pixel: sector s, horizontal range [m], height above the plane [m]. Inline: called for every pixel.
    void add(int s, float rangeM, float z) noexcept
    {
        const float x = rangeM / config_.binM;
        if (s < 0 || s >= sectors_ || !(x >= 0.0F && x < static_cast<float>(bins_))) {
            return;
        }
        const Band& band = bands_[static_cast<std::size_t>(x)];
        if (!(std::abs(z) < band.halfM)) {
            return;
        }
        // Nearest height bin: z / kHeightBinM + centre + 0.5 is positive here (|z| < halfM), so truncation rounds.
        // NOLINTNEXTLINE(bugprone-incorrect-roundings): the value is positive (above), where this rounds correctly
        const int h = static_cast<int>(z / kHeightBinM + static_cast<float>(band.centre) + 0.5F);
        std::uint16_t& count =
            histogram_[static_cast<std::size_t>(s) * static_cast<std::size_t>(perSector_) +
                       static_cast<std::size_t>(band.first) + static_cast<std::size_t>(std::min(h, 2 * band.centre))];
        count = count == std::numeric_limits<std::uint16_t>::max() ? count : static_cast<std::uint16_t>(count + 1);
    }
    /// Fits every sector's profile from the pixels added since clear().
    void fit() noexcept;
    /// The profile's height [m] above the plane in sector s at rangeM (0 before fit()).
    [[nodiscard]] float at(int s, float rangeM) const noexcept;

private:
    static constexpr float kHeightBinM = 0.01F;
    /// The peak of bin `bin`'s heights within +-bandM of centreM [m] (from at least minPoints pixels there).
    [[nodiscard]] bool mode(int s, int bin, float centreM, float& z) const noexcept;
    /// The median of that mode and those of the nearest bins with one on each side (at most two away).
    [[nodiscard]] bool filteredMode(int s, int b, float centreM, float& z) const noexcept;
    void fitSector(int s) noexcept;
    /// A range bin's height bins: 2 centre + 1 of them from `first` in its sector's histogram, height 0 at centre.
    struct Band {
        int first = 0;
        int centre = 0;
        float halfM = 0.0F; ///< [m] heights counted, +-
    };
    /// The profile's bound [m] at range r: +-(maxOffsetM + maxSlope r).
    [[nodiscard]] float maxOffset(float rangeM) const noexcept
    {
        return config_.maxOffsetM + config_.maxSlope * rangeM;
    }

    LocalGroundConfig config_;
    int sectors_ = 0;
    int bins_ = 0;                         ///< range bins
    int perSector_ = 0;                    ///< histogram bins per sector (all its range bins' bands)
    std::vector<Band> bands_;              ///< [range bin]
    std::vector<std::uint16_t> histogram_; ///< [sector][range bin: its band's height bins]
    std::vector<float> profile_;           ///< [sector][range bin] height at the bin centre [m]
};

} // namespace ugv::vision
