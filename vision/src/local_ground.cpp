#include "ugv/vision/local_ground.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace ugv::vision {

void LocalGround::configure(const LocalGroundConfig& config, int sectors, float maxRangeM)
{
    config_ = config;
    sectors_ = sectors;
    bins_ = std::max(1, static_cast<int>(std::ceil(maxRangeM / config.binM)));
    bands_.assign(static_cast<std::size_t>(bins_), Band{});
    perSector_ = 0;
    for (int b = 0; b < bins_; ++b) {
        // As wide as the profile's bound at the bin's far end, plus the band it looks within.
        Band& band = bands_[static_cast<std::size_t>(b)];
        band.halfM = config.bandM + config.maxOffsetM + config.maxSlope * static_cast<float>(b + 1) * config.binM;
        band.centre = static_cast<int>(std::ceil(band.halfM / kHeightBinM));
        band.first = perSector_;
        perSector_ += 2 * band.centre + 1;
    }
    histogram_.assign(static_cast<std::size_t>(sectors_) * static_cast<std::size_t>(perSector_), 0U);
    profile_.assign(static_cast<std::size_t>(sectors_) * static_cast<std::size_t>(bins_), 0.0F);
}

void LocalGround::clear() noexcept
{
    std::fill(histogram_.begin(), histogram_.end(), 0U);
    std::fill(profile_.begin(), profile_.end(), 0.0F);
}

bool LocalGround::mode(int s, int bin, float centreM, float& z) const noexcept
{
    // The heights within +-bandM of centreM that the bin's band holds.
    const Band& band = bands_[static_cast<std::size_t>(bin)];
    const std::uint16_t* h = &histogram_[static_cast<std::size_t>(s) * static_cast<std::size_t>(perSector_) +
                                         static_cast<std::size_t>(band.first)];
    const float centre = centreM / kHeightBinM + static_cast<float>(band.centre);
    const float halfWidth = config_.bandM / kHeightBinM;
    const int lo = std::max(0, static_cast<int>(std::ceil(centre - halfWidth)));
    const int hi = std::min(2 * band.centre, static_cast<int>(std::floor(centre + halfWidth)));
    int total = 0;
    int best = -1;
    int bestSum = 0;
    for (int i = lo; i <= hi; ++i) {
        total += h[i];
        // The peak of the histogram smoothed over three height bins (3 cm).
        const int sum = h[i] + (i > lo ? h[i - 1] : 0) + (i < hi ? h[i + 1] : 0);
        if (sum > bestSum) {
            bestSum = sum;
            best = i;
        }
    }
    if (total < config_.minPoints || best < 0) {
        return false;
    }
    double sum = 0.0;
    double weighted = 0.0;
    for (int i = std::max(lo, best - 1); i <= std::min(hi, best + 1); ++i) {
        sum += h[i];
        weighted += static_cast<double>(h[i]) * (i - band.centre) * kHeightBinM;
    }
    z = static_cast<float>(weighted / sum);
    return true;
}

bool LocalGround::filteredMode(int s, int b, float centreM, float& z) const noexcept
{
    // A feature one bin deep (a trench's far wall, the foot of a face) is not the ground's course, a grade or a
    // camber that goes on is: the median of this bin's mode and those of the nearest bins with one on each side
    // (at most two bins away), all looked for near the same height.
    if (!mode(s, b, centreM, z)) {
        return false;
    }
    std::array<float, 3> v{z, z, z};
    int count = 1;
    for (int k = b - 1; k >= std::max(0, b - 2); --k) {
        if (mode(s, k, centreM, v[static_cast<std::size_t>(count)])) {
            ++count;
            break;
        }
    }
    for (int k = b + 1; k <= std::min(bins_ - 1, b + 2); ++k) {
        if (mode(s, k, centreM, v[static_cast<std::size_t>(count)])) {
            ++count;
            break;
        }
    }
    if (count == 3) { // else an end of the seen ground: nothing to filter against
        z = std::max(std::min(v[0], v[1]), std::min(std::max(v[0], v[1]), v[2]));
    }
    return true;
}

void LocalGround::fitSector(int s) noexcept
{
    // From the vehicle outwards: the ground is the surface connected to the nearest ground seen. A bin whose
    // filtered mode, looked for within +-bandM of the extrapolation, follows it (within stepM plus maxSlope over one
    // bin) is ground and moves the estimate; one that jumps (a kerb, a pavement, a face, a drop) is not, and the last
    // ground level holds (also over the bins after it: a pavement stays a step however long it runs). Looking near
    // the extrapolation, not over the whole band, keeps an obstacle's many pixels out of the ground's mode while a
    // grade that goes on is followed.
    float* out = &profile_[static_cast<std::size_t>(s) * static_cast<std::size_t>(bins_)];
    // The walk starts at the nearest bin whose level the next bin with a mode confirms (a near curb's top, one bin
    // deep, is not the ground's level; modes looked for within bandM of the plane), within maxOffsetM of the plane;
    // without one, on the plane.
    const float tolerance = config_.stepM + config_.maxSlope * config_.binM;
    float level = 0.0F; // [m] at lastR
    float slope = 0.0F; // [m/m]
    float lastR = 0.0F;
    bool confirmed = false;
    for (int b = 0, previous = -1; b < bins_ && !confirmed; ++b) {
        float z = 0.0F;
        if (!filteredMode(s, b, 0.0F, z)) {
            continue;
        }
        confirmed = previous >= 0 && std::abs(z - level) <= tolerance; // bin `previous` starts the walk
        if (!confirmed) {
            previous = std::abs(z) <= config_.maxOffsetM ? b : -1;
            level = z;
            lastR = (static_cast<float>(b) + 0.5F) * config_.binM;
        }
    }
    if (!confirmed) {
        level = 0.0F;
        lastR = 0.0F;
    }
    // A grade is the vehicle's own ground going on: the bound widens with the range (maxOffset(r)) only for a walk
    // that starts on the plane; one that starts on a raised or sunken surface (a pavement, where the road is out of
    // view) keeps +-maxOffsetM, so a pavement that rises away is not taken for the road.
    const bool fromThePlane = std::abs(level) <= config_.stepM;
    for (int b = 0; b < bins_; ++b) {
        const float r = (static_cast<float>(b) + 0.5F) * config_.binM;
        const float predicted = level + slope * (r - lastR);
        float z = 0.0F;
        if (filteredMode(s, b, predicted, z) && std::abs(z - predicted) <= tolerance) {
            const float newSlope =
                r > lastR ? std::clamp((z - level) / (r - lastR), -config_.maxSlope, config_.maxSlope) : 0.0F;
            slope += 0.5F * (newSlope - slope);
            level = z;
            lastR = r;
        }
        const float bound = fromThePlane ? maxOffset(r) : config_.maxOffsetM;
        out[b] = std::clamp(level, -bound, bound); // held past the last ground bin
    }
}

void LocalGround::fit() noexcept
{
    for (int s = 0; s < sectors_; ++s) {
        fitSector(s);
    }
}

float LocalGround::at(int s, float rangeM) const noexcept
{
    if (s < 0 || s >= sectors_ || bins_ < 1) {
        return 0.0F;
    }
    const float* p = &profile_[static_cast<std::size_t>(s) * static_cast<std::size_t>(bins_)];
    const float x = rangeM / config_.binM - 0.5F;
    if (!(x > 0.0F)) {
        return p[0];
    }
    const int b = static_cast<int>(x);
    if (b >= bins_ - 1) {
        return p[bins_ - 1];
    }
    const float t = x - static_cast<float>(b);
    return p[b] + t * (p[b + 1] - p[b]);
}

} // namespace ugv::vision
