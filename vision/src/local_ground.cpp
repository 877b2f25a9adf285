#include "ugv/vision/local_ground.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace ugv::vision {
namespace {

} // namespace

void LocalGround::configure(const LocalGroundConfig& config, int sectors, float maxRangeM)
{
    config_ = config;
    sectors_ = sectors;
    bins_ = std::max(1, static_cast<int>(std::ceil(maxRangeM / config.binM)));
    heightBins_ = 2 * static_cast<int>(std::ceil(config.bandM / kHeightBinM)) + 1;
    histogram_.assign(static_cast<std::size_t>(sectors_) * static_cast<std::size_t>(bins_) *
                          static_cast<std::size_t>(heightBins_),
                      0U);
    profile_.assign(static_cast<std::size_t>(sectors_) * static_cast<std::size_t>(bins_), 0.0F);
}

void LocalGround::clear() noexcept
{
    std::fill(histogram_.begin(), histogram_.end(), 0U);
    std::fill(profile_.begin(), profile_.end(), 0.0F);
}

bool LocalGround::mode(int s, int bin, float& z) const noexcept
{
    const std::uint16_t* h =
        &histogram_[(static_cast<std::size_t>(s) * static_cast<std::size_t>(bins_) + static_cast<std::size_t>(bin)) *
                    static_cast<std::size_t>(heightBins_)];
    int total = 0;
    int best = -1;
    int bestSum = 0;
    for (int i = 0; i < heightBins_; ++i) {
        total += h[i];
        // The peak of the histogram smoothed over three height bins (3 cm).
        const int sum = h[i] + (i > 0 ? h[i - 1] : 0) + (i + 1 < heightBins_ ? h[i + 1] : 0);
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
    const int centre = heightBins_ / 2; // the bin of height 0
    for (int i = std::max(0, best - 1); i <= std::min(heightBins_ - 1, best + 1); ++i) {
        sum += h[i];
        weighted += static_cast<double>(h[i]) * (i - centre) * kHeightBinM;
    }
    z = static_cast<float>(weighted / sum);
    return true;
}

void LocalGround::fitSector(int s) noexcept
{
    // The modes, median-filtered over three bins with a mode: a feature one bin deep (a trench's far wall, the foot
    // of a face) is not the ground's course, a grade or a camber that goes on is.
    constexpr int kMaxBins = 512;
    std::array<float, kMaxBins> modes{};
    std::array<bool, kMaxBins> have{};
    const int n = std::min(bins_, kMaxBins);
    for (int b = 0; b < n; ++b) {
        have[static_cast<std::size_t>(b)] = mode(s, b, modes[static_cast<std::size_t>(b)]);
    }
    // From the vehicle outwards: the ground is the surface connected to the nearest ground seen. A bin whose
    // filtered mode follows the extrapolation (within stepM plus maxSlope over one bin) is ground and moves the
    // estimate; one that jumps (a kerb, a pavement, a face, a drop) is not, and the last ground level holds (also
    // over the bins after it: a pavement stays a step however long it runs).
    float* out = &profile_[static_cast<std::size_t>(s) * static_cast<std::size_t>(bins_)];
    // The walk starts at the nearest bin whose level the next bin with a mode confirms (a near curb's top, one bin
    // deep, is not the ground's level), within maxOffsetM of the plane; without one, on the plane.
    const float tolerance = config_.stepM + config_.maxSlope * config_.binM;
    float level = 0.0F; // [m] at lastR
    float slope = 0.0F; // [m/m]
    float lastR = 0.0F;
    bool confirmed = false;
    for (int b = 0, previous = -1; b < n && !confirmed; ++b) {
        float z = 0.0F;
        if (!filteredMode(modes.data(), have.data(), n, b, z)) {
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
    for (int b = 0; b < bins_; ++b) {
        const float r = (static_cast<float>(b) + 0.5F) * config_.binM;
        float z = 0.0F;
        const bool valid = b < n && filteredMode(modes.data(), have.data(), n, b, z);
        const float predicted = level + slope * (r - lastR);
        if (valid && std::abs(z - predicted) <= tolerance) {
            const float newSlope =
                r > lastR ? std::clamp((z - level) / (r - lastR), -config_.maxSlope, config_.maxSlope) : 0.0F;
            slope += 0.5F * (newSlope - slope);
            level = z;
            lastR = r;
        }
        out[b] = std::clamp(level, -config_.maxOffsetM, config_.maxOffsetM); // held past the last ground bin
    }
}

bool LocalGround::filteredMode(const float* modes, const bool* have, int n, int b, float& z) noexcept
{
    if (!have[b]) {
        return false;
    }
    // The nearest bin with a mode on each side (at most two bins away), with this one: their median.
    std::array<float, 3> v{modes[b], modes[b], modes[b]};
    int count = 1;
    for (int k = b - 1; k >= std::max(0, b - 2); --k) {
        if (have[k]) {
            v[static_cast<std::size_t>(count++)] = modes[k];
            break;
        }
    }
    for (int k = b + 1; k <= std::min(n - 1, b + 2); ++k) {
        if (have[k]) {
            v[static_cast<std::size_t>(count++)] = modes[k];
            break;
        }
    }
    if (count < 3) {
        z = modes[b]; // an end of the seen ground: nothing to filter against
        return true;
    }
    z = std::max(std::min(v[0], v[1]), std::min(std::max(v[0], v[1]), v[2]));
    return true;
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
