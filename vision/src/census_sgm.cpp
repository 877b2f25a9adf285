#include "ugv/vision/census_sgm.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>

#include <opencv2/calib3d.hpp>

#include "census_sgm.simd.hpp"

namespace ugv::vision {
namespace {

constexpr int kBorderX = 4;             ///< census window 9 wide
constexpr int kBorderY = 3;             ///< and 7 high
constexpr int kPlanes = 4;              ///< census bytes per pixel (31 bits used)
constexpr int kRowPlanes = kPlanes + 1; ///< and the intensity >> kIntensityShift
constexpr int kIntensityShift = 2;
constexpr int kPad = 16; ///< 255 bytes before and after each path entry
constexpr int kMaxCensusCost = CensusSgm::kCensusBits;
constexpr int kMaxIntensityClip = 31;
constexpr int kMaxDisparities = 256;
constexpr int kPaths = 3; ///< rows kept for the top, top-left and top-right paths
constexpr std::uint16_t kNoCost = 0xFFFF;
/// Search ranges start at a multiple of this (the kernels run over whole 16-disparity blocks).
constexpr int kRangeBlock = 16;
/// Entries just below a row's first searched disparity that are set to 255 after each path step, so that the next
/// row's top paths (which read up to 1 + 5 entries below their own first disparity: the neighbour, and the ground
/// prior's step of at most 5) see saturated costs there, not a value left by an earlier row.
constexpr int kRangeGuard = 8;
static_assert(kRangeGuard <= kRangeBlock && kRangeGuard <= kPad);

Error configError(const std::string& what)
{
    return Error{"CensusSgmConfig", what, "see vision/include/ugv/vision/census_sgm.hpp for the valid ranges"};
}

// ---- scalar references of the kernels in census_sgm.simd.hpp (same saturating arithmetic) ----

std::uint8_t saturate(int v) noexcept
{
    return static_cast<std::uint8_t>(std::min(v, 255));
}

void censusRowScalar(const std::uint8_t* centre, std::ptrdiff_t step, int begin, int width, std::uint8_t* planes,
                     int planeStride) noexcept
{
    for (int x = begin; x < width; ++x) {
        std::uint8_t acc[kPlanes] = {0, 0, 0, 0};
        int bit = 0;
        for (int dy = 0; dy <= kBorderY; ++dy) {
            for (int dx = (dy == 0 ? 1 : -kBorderX); dx <= kBorderX; ++dx, ++bit) {
                const bool greater = centre[dy * step + x + dx] > centre[-dy * step + x - dx];
                std::uint8_t& plane = acc[bit >> 3];
                plane = static_cast<std::uint8_t>((plane << 1) | (greater ? 1 : 0));
            }
        }
        for (int p = 0; p < kPlanes; ++p) {
            planes[p * planeStride + x] = acc[p];
        }
    }
}

void costPixelScalar(const std::uint8_t left[kRowPlanes], const std::uint8_t* right, int planeStride, int d, int clip,
                     std::uint8_t* cost) noexcept
{
    for (int k = 0; k < d; ++k) {
        int c = std::min(std::abs(left[kPlanes] - right[kPlanes * planeStride + k]), clip);
        for (int p = 0; p < kPlanes; ++p) {
            c += std::popcount(static_cast<unsigned>(left[p] ^ right[p * planeStride + k]));
        }
        cost[k] = static_cast<std::uint8_t>(c);
    }
}

std::uint8_t pathStepScalar(const std::uint8_t* prev, int minPrev, const std::uint8_t* cost, std::uint8_t* out, int d,
                            int p1, int p2) noexcept
{
    const int bound = std::min(255, minPrev + p2);
    int acc = 255;
    for (int k = 0; k < d; ++k) {
        const int step = saturate(std::min(prev[k - 1], prev[k + 1]) + p1);
        const int best = std::min({static_cast<int>(prev[k]), step, bound});
        const std::uint8_t l = saturate(best - minPrev + cost[k]);
        out[k] = l;
        acc = std::min(acc, static_cast<int>(l));
    }
    return static_cast<std::uint8_t>(acc);
}

template <std::size_t N>
void sumRowsScalar(const std::array<const std::uint8_t*, N>& rows, std::uint16_t* sum, int d) noexcept
{
    for (int k = 0; k < d; ++k) {
        int total = 0;
        for (const std::uint8_t* row : rows) {
            total += row[k];
        }
        sum[k] = static_cast<std::uint16_t>(total);
    }
}

std::uint16_t addAndMinScalar(const std::uint8_t* a, std::uint16_t* sum, int d) noexcept
{
    std::uint16_t acc = kNoCost;
    for (int k = 0; k < d; ++k) {
        sum[k] = static_cast<std::uint16_t>(sum[k] + a[k]);
        acc = std::min(acc, sum[k]);
    }
    return acc;
}

/// The least of sum[0, d) outside [lo, hi] (kNoCost when nothing is outside). Only the blocks that overlap [lo, hi]
/// are masked, in registers: writing the excluded entries over and loading them back would stall every pixel on
/// store forwarding.
std::uint16_t minOutside(const std::uint16_t* sum, int d, int lo, int hi, bool useSimd) noexcept
{
#if (CV_SIMD || CV_SIMD_SCALABLE)
    if (useSimd) {
        using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
        const int lanes = simd::VTraits<v_uint16>::vlanes();
        alignas(64) static constexpr std::uint16_t kIota[32] = {0,  1,  2,  3,  4,  5,  6,  7,  8,  9,  10,
                                                                11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21,
                                                                22, 23, 24, 25, 26, 27, 28, 29, 30, 31};
        static_assert(simd::VTraits<v_uint16>::max_nlanes <= 32);
        const v_uint16 none = vx_setall_u16(kNoCost);
        const v_uint16 span = vx_setall_u16(static_cast<std::uint16_t>(hi - lo));
        v_uint16 acc = none;
        for (int k = 0; k < d; k += lanes) {
            v_uint16 v = vx_load(sum + k);
            if (k <= hi && k + lanes > lo) {
                // Lane index - lo, wrapping below lo: inside [lo, hi] exactly when it is <= hi - lo.
                const v_uint16 offset = v_sub_wrap(vx_load(kIota), vx_setall_u16(static_cast<std::uint16_t>(lo - k)));
                v = v_select(simd::v_gt(offset, span), v, none);
            }
            acc = v_min(acc, v);
        }
        return v_reduce_min(acc);
    }
#endif
    std::uint16_t acc = kNoCost;
    for (int k = 0; k < d; ++k) {
        if (k < lo || k > hi) {
            acc = std::min(acc, sum[k]);
        }
    }
    return acc;
}

int firstIndexOf(const std::uint16_t* sum, int d, std::uint16_t value, bool useSimd) noexcept
{
    int k = 0;
#if (CV_SIMD || CV_SIMD_SCALABLE)
    if (useSimd) {
        using namespace cv; // NOLINT(google-build-using-namespace): universal intrinsics are free functions in cv
        const int lanes = simd::VTraits<v_uint16>::vlanes();
        const v_uint16 target = vx_setall_u16(value);
        for (; k + lanes <= d; k += lanes) {
            const v_uint16 equal = simd::v_eq(vx_load(sum + k), target);
            if (v_check_any(equal)) {
                return k + v_scan_forward(equal); // the first equal lane
            }
        }
    }
#endif
    while (k < d && sum[k] != value) {
        ++k;
    }
    return k;
}

} // namespace

Result<CensusSgm, Error> CensusSgm::create(const CensusSgmConfig& config, cv::Size size)
{
    const int d = config.numDisparities;
    if (d < 16 || d > kMaxDisparities || d % 16 != 0) {
        return Unexpected(configError("numDisparities " + std::to_string(d) + " is not a multiple of 16 in 16..256"));
    }
    if (config.intensityClip < 0 || config.intensityClip > kMaxIntensityClip) {
        return Unexpected(configError("intensityClip " + std::to_string(config.intensityClip) + " is not in 0..31"));
    }
    // A path cost is at most maxCost + p2 and must stay below 255 (8-bit paths): minPrev <= maxCost.
    const int maxP2 = 254 - kMaxCensusCost - config.intensityClip;
    if (config.p1 < 1 || config.p2 <= config.p1 || config.p2 > maxP2) {
        return Unexpected(configError("p1 " + std::to_string(config.p1) + ", p2 " + std::to_string(config.p2) +
                                      ": need 1 <= p1 < p2 <= " + std::to_string(maxP2) +
                                      " (254 - 31 - intensityClip)"));
    }
    if (config.uniquenessRatio < 0 || config.uniquenessRatio > 99 || config.speckleWindowSize < 0 ||
        config.speckleRange < 0) {
        return Unexpected(configError("uniquenessRatio (0..99) or speckle settings (>= 0) out of range"));
    }
    if (config.paths != 2 && config.paths != 3 && config.paths != 5) {
        return Unexpected(configError("paths " + std::to_string(config.paths) + " is not 2, 3 or 5"));
    }
    if (!(config.groundPriorTolerancePx >= 0.0 && config.groundPriorTolerancePx <= 16.0)) {
        return Unexpected(configError("groundPriorTolerancePx " + std::to_string(config.groundPriorTolerancePx) +
                                      " is not in [0, 16]"));
    }
    if (size.width <= d || size.height < 1) {
        return Unexpected(configError("image " + std::to_string(size.width) + "x" + std::to_string(size.height) +
                                      " is not wider than numDisparities " + std::to_string(d)));
    }
    CensusSgm sut;
    sut.config_ = config;
    sut.width_ = size.width;
    sut.height_ = size.height;
    sut.d_ = d;
    sut.x0_ = d - 1;
    sut.cols_ = size.width - sut.x0_;
    sut.stride_ = d + 2 * kPad;
    const auto w = static_cast<std::size_t>(size.width);
    const auto h = static_cast<std::size_t>(size.height);
    const auto cols = static_cast<std::size_t>(sut.cols_);
    const auto du = static_cast<std::size_t>(d);
    sut.padded_.assign((h + 2 * kBorderY) * (w + 2 * kBorderX), 0);
    sut.censusRow_.assign(kRowPlanes * w, 0);
    sut.leftCensus_.assign(h * kRowPlanes * w, 0);
    sut.rightCensus_.assign(h * kRowPlanes * w, 0);
    sut.cost_.assign(cols * du, 0);
    sut.paths_.assign(2 * kPaths * (cols + 2) * static_cast<std::size_t>(sut.stride_), 255);
    sut.pathMin_.assign(2 * kPaths * (cols + 2), 255);
    sut.horizontal_.assign(3 * static_cast<std::size_t>(sut.stride_), 255);
    sut.zeros_.assign(du, 0);
    sut.sum_.assign(cols * du, 0);
    sut.disp2Cost_.assign(w, kNoCost);
    sut.disp2_.assign(w, kInvalid);
    sut.rowLo_.assign(h, 0);
    // cv::filterSpeckles reuses a continuous buffer of at least width * height * (4 + 4 + 1) bytes.
    sut.speckleBuffer_.create(1, static_cast<int>(w * h * 9), CV_8UC1);
    return sut;
}

std::uint8_t* CensusSgm::pathEntry(int half, int path, int entry) noexcept
{
    return paths_.data() + entryIndex(half, path, entry) * static_cast<std::size_t>(stride_) + kPad;
}

void CensusSgm::census(ConstImageViewU8 image, std::uint8_t* planes, bool reversed) noexcept
{
    const int paddedStride = width_ + 2 * kBorderX;
    for (int r = -kBorderY; r < height_ + kBorderY; ++r) {
        const std::uint8_t* src = image.row(std::clamp(r, 0, height_ - 1));
        std::uint8_t* dst = padded_.data() + static_cast<std::ptrdiff_t>(r + kBorderY) * paddedStride;
        std::memset(dst, src[0], kBorderX);
        std::memcpy(dst + kBorderX, src, static_cast<std::size_t>(width_));
        std::memset(dst + kBorderX + width_, src[width_ - 1], kBorderX);
    }
    for (int y = 0; y < height_; ++y) {
        const std::uint8_t* centre =
            padded_.data() + static_cast<std::ptrdiff_t>(y + kBorderY) * paddedStride + kBorderX;
        int x = 0;
#if (CV_SIMD || CV_SIMD_SCALABLE)
        if (config_.simd) {
            x = simd::censusRowSimd(centre, paddedStride, width_, censusRow_.data(), width_);
        }
#endif
        censusRowScalar(centre, paddedStride, x, width_, censusRow_.data(), width_);
        std::uint8_t* intensity = censusRow_.data() + static_cast<std::ptrdiff_t>(kPlanes) * width_;
        for (int i = 0; i < width_; ++i) {
            intensity[i] = static_cast<std::uint8_t>(centre[i] >> kIntensityShift);
        }
        std::uint8_t* out = planes + static_cast<std::ptrdiff_t>(y) * kRowPlanes * width_;
        if (!reversed) {
            std::memcpy(out, censusRow_.data(), censusRow_.size());
            continue;
        }
        for (int p = 0; p < kRowPlanes; ++p) {
            const std::uint8_t* in = censusRow_.data() + static_cast<std::ptrdiff_t>(p) * width_;
            std::uint8_t* plane = out + static_cast<std::ptrdiff_t>(p) * width_;
            int done = 0;
#if (CV_SIMD || CV_SIMD_SCALABLE)
            if (config_.simd) {
                done = simd::reverseRowSimd(in, width_, plane);
            }
#endif
            std::reverse_copy(in + done, in + width_, plane);
        }
    }
}

void CensusSgm::costRow(int y) noexcept
{
    const std::uint8_t* left = leftCensus_.data() + static_cast<std::ptrdiff_t>(y) * kRowPlanes * width_;
    const std::uint8_t* right = rightCensus_.data() + static_cast<std::ptrdiff_t>(y) * kRowPlanes * width_;
    const int lo = rowLo_[static_cast<std::size_t>(y)];
    const int n = d_ - lo;
    for (int i = 0; i < cols_; ++i) {
        const int x = x0_ + i;
        const std::uint8_t bytes[kRowPlanes] = {left[x], left[width_ + x], left[2 * width_ + x], left[3 * width_ + x],
                                                left[4 * width_ + x]};
        // Right column x - k is reversed index width - 1 - x + k: ascending in k.
        const std::uint8_t* r = right + (width_ - 1 - x) + lo;
        std::uint8_t* cost = cost_.data() + static_cast<std::ptrdiff_t>(i) * n; // entry k at k - lo
#if (CV_SIMD || CV_SIMD_SCALABLE)
        if (config_.simd) {
            simd::costPixelSimd(bytes, r, width_, n, config_.intensityClip, cost);
            continue;
        }
#endif
        costPixelScalar(bytes, r, width_, n, config_.intensityClip, cost);
    }
}

void CensusSgm::setGroundPrior(double a, double b, double c) noexcept
{
    if (!(std::isfinite(a) && std::isfinite(b) && std::isfinite(c)) || std::abs(b) > 4.0) {
        groundPrior_ = false; // a step over 4 px a row would leave the path's pads
        return;
    }
    groundPrior_ = true;
    groundA_ = a;
    groundB_ = b;
    groundC_ = c;
}

void CensusSgm::setSearchFloor(double a, double b, double c) noexcept
{
    searchFloor_ = std::isfinite(a) && std::isfinite(b) && std::isfinite(c);
    floorA_ = a;
    floorB_ = b;
    floorC_ = c;
}

void CensusSgm::searchRanges() noexcept
{
    std::int64_t searched = 0;
    for (int y = 0; y < height_; ++y) {
        int lo = 0;
        if (searchFloor_) {
            // The smallest floor over the matched columns: f is linear in x, so at one of the two ends.
            const double atRow = floorB_ * y + floorC_ + std::min(floorA_ * x0_, floorA_ * (width_ - 1));
            const int floorPx = static_cast<int>(std::clamp(atRow, 0.0, static_cast<double>(d_)));
            lo = std::min(floorPx / kRangeBlock * kRangeBlock, d_ - kRangeBlock);
        }
        rowLo_[static_cast<std::size_t>(y)] = lo;
        searched += d_ - lo;
    }
    searchedFraction_ = static_cast<double>(searched) / (static_cast<double>(d_) * height_);
}

/// One row's search range [lo, lo + n) and the path step over it. The path entries keep the full range's layout
/// (entry k at index k: the next row reads them at its own range); cost_ and sum_ hold only the row's n entries per
/// column (entry k at k - lo), so that a shorter range also touches less memory.
struct CensusSgm::RowRange {
    int lo = 0;
    int n = 0;
    int p1 = 0;
    int p2 = 0;
    bool simd = false;

    /// out = the path's costs at this column from prev, its costs at the previous column; @return min over out.
    std::uint8_t step(const std::uint8_t* prev, int minPrev, const std::uint8_t* cost, std::uint8_t* out) const noexcept
    {
#if (CV_SIMD || CV_SIMD_SCALABLE)
        if (simd) {
            return simd::pathStepSimd(prev + lo, minPrev, cost, out + lo, n, p1, p2);
        }
#endif
        return pathStepScalar(prev + lo, minPrev, cost, out + lo, n, p1, p2);
    }

    /// Saturates the kRangeGuard entries below lo (see kRangeGuard).
    void guard(std::uint8_t* entry) const noexcept
    {
        if (lo > 0) {
            std::memset(entry + lo - kRangeGuard, 255, kRangeGuard);
        }
    }
};

std::size_t CensusSgm::entryIndex(int half, int path, int entry) const noexcept
{
    return static_cast<std::size_t>((half * kPaths + path) * (cols_ + 2) + entry);
}

std::uint8_t* CensusSgm::horizontalEntry(int i) noexcept
{
    return horizontal_.data() + (1 + (i & 1)) * stride_ + kPad;
}

void CensusSgm::aggregateRow(std::int16_t* disp, const std::int16_t* above, int y) noexcept
{
    const int lo = rowLo_[static_cast<std::size_t>(y)];
    const RowRange range{lo, d_ - lo, config_.p1, config_.p2, config_.simd};
    // A row that searches lower than the row above: the row above's entries below its range hold values of older
    // rows. Saturate them (rare: the floor falls down the image only on a plane with b < 0).
    const int loAbove = y > 0 ? rowLo_[static_cast<std::size_t>(y - 1)] : 0;
    if (loAbove > lo && config_.paths >= 3) {
        const int from = std::max(0, lo - kRangeGuard);
        for (int path = 0; path < kPaths; ++path) {
            for (int e = 1; e <= cols_; ++e) {
                std::memset(pathEntry(parity_, path, e) + from, 255, static_cast<std::size_t>(loAbove - from));
            }
        }
    }
    range.guard(horizontalEntry(0)); // the horizontal paths read the entry below lo of the previous column's
    range.guard(horizontalEntry(1));
    forwardPaths(range, above, y);
    backwardPaths(range, disp);
    parity_ = 1 - parity_;
}

void CensusSgm::forwardPaths(RowRange range, const std::int16_t* above, int y) noexcept
{
    const bool vertical = config_.paths >= 3;
    const bool diagonals = config_.paths == 5;
    const int lo = range.lo;
    const int n = range.n;
    const int prev = parity_;
    const int cur = 1 - parity_;
    // The ground's step from the row above to this one (see setGroundPrior); the row above's ground at column x is
    // aboveGround0 + groundA_ x.
    const int groundStep = groundPrior_ && above != nullptr
                               ? static_cast<int>(std::lround(groundB_ * y) - std::lround(groundB_ * (y - 1)))
                               : 0;
    const double aboveGround0 = groundB_ * (y - 1) + groundC_;
    const double tolerance16 = config_.groundPriorTolerancePx * kScale;
    const std::uint8_t* hPrev = horizontal_.data() + kPad; // the border: never written, all 255
    int hMin = 255;
    for (int i = 0; i < cols_; ++i) {
        const int e = i + 1;
        const std::uint8_t* cost = cost_.data() + static_cast<std::ptrdiff_t>(i) * n;
        std::uint8_t* h = horizontalEntry(i);
        hMin = range.step(hPrev, hMin, cost, h);
        hPrev = h;
        const std::uint8_t* top = zeros_.data();
        if (vertical) {
            std::uint8_t* t = pathEntry(cur, 0, e);
            int shift = 0;
            if (groundStep != 0) {
                const int x = x0_ + i;
                const double onGround = above[x] >= 0 ? above[x] - kScale * (aboveGround0 + groundA_ * x) : 1e9;
                shift = std::abs(onGround) < tolerance16 ? groundStep : 0;
            }
            // Entry k continues entry k - shift of the row above; the pads (255) stand in past the range ends.
            pathMin_[entryIndex(cur, 0, e)] =
                range.step(pathEntry(prev, 0, e) - shift, pathMin_[entryIndex(prev, 0, e)], cost, t);
            range.guard(t);
            top = t;
        }
        const std::uint8_t* topLeft = nullptr; // the diagonals' rows: set and summed with five paths only
        const std::uint8_t* topRight = nullptr;
        if (diagonals) {
            std::uint8_t* tl = pathEntry(cur, 1, e);
            std::uint8_t* tr = pathEntry(cur, 2, e);
            pathMin_[entryIndex(cur, 1, e)] =
                range.step(pathEntry(prev, 1, e - 1), pathMin_[entryIndex(prev, 1, e - 1)], cost, tl);
            pathMin_[entryIndex(cur, 2, e)] =
                range.step(pathEntry(prev, 2, e + 1), pathMin_[entryIndex(prev, 2, e + 1)], cost, tr);
            range.guard(tl);
            range.guard(tr);
            topLeft = tl;
            topRight = tr;
        }
        std::uint16_t* sum = sum_.data() + static_cast<std::ptrdiff_t>(i) * n;
        const auto sumRows = [&](const auto& rows) {
#if (CV_SIMD || CV_SIMD_SCALABLE)
            if (range.simd) {
                simd::sumRowsSimd(rows, sum, n);
                return;
            }
#endif
            sumRowsScalar(rows, sum, n);
        };
        if (diagonals) {
            sumRows(std::array<const std::uint8_t*, 4>{h + lo, top + lo, topLeft + lo, topRight + lo});
        } else { // the horizontal path and the top one (zeros with two paths): no rows of zeros for the diagonals
            sumRows(std::array<const std::uint8_t*, 2>{h + lo, top + lo});
        }
    }
}

void CensusSgm::backwardPaths(RowRange range, std::int16_t* disp) noexcept
{
    const int lo = range.lo;
    const int n = range.n;
    std::fill(disp2Cost_.begin(), disp2Cost_.end(), kNoCost);
    std::fill(disp2_.begin(), disp2_.end(), kInvalid);
    const std::uint8_t* hPrev = horizontal_.data() + kPad; // the border: never written, all 255
    int hMin = 255;
    for (int i = cols_ - 1; i >= 0; --i) {
        const std::uint8_t* cost = cost_.data() + static_cast<std::ptrdiff_t>(i) * n;
        std::uint8_t* h = horizontalEntry(i);
        hMin = range.step(hPrev, hMin, cost, h);
        hPrev = h;
        std::uint16_t* sum = sum_.data() + static_cast<std::ptrdiff_t>(i) * n;
        std::uint16_t minSum = 0;
#if (CV_SIMD || CV_SIMD_SCALABLE)
        if (range.simd) {
            minSum = simd::addAndMinSimd(h + lo, sum, n);
        } else {
            minSum = addAndMinScalar(h + lo, sum, n);
        }
#else
        minSum = addAndMinScalar(h + lo, sum, n);
#endif
        winner(i, lo, minSum, disp);
    }
}

void CensusSgm::winner(int i, int lo, std::uint16_t minSum, std::int16_t* disp) noexcept
{
    // The row's sums: n = d_ - lo entries per column, disparity lo + j at j (only the searched ones).
    const int n = d_ - lo;
    std::uint16_t* sum = sum_.data() + static_cast<std::ptrdiff_t>(i) * n;
    const int x = x0_ + i;
    const int j = firstIndexOf(sum, n, minSum, config_.simd);
    const int best = lo + j;
    // Second best outside best +- 1.
    const std::uint16_t second = minOutside(sum, n, j - 1, j + 1, config_.simd);
    if (static_cast<int>(second) * (100 - config_.uniquenessRatio) <= static_cast<int>(minSum) * 100) {
        disp[x] = kInvalid;
        return;
    }
    const int x2 = x - best;
    if (disp2Cost_[static_cast<std::size_t>(x2)] > minSum) {
        disp2Cost_[static_cast<std::size_t>(x2)] = minSum;
        disp2_[static_cast<std::size_t>(x2)] = static_cast<std::int16_t>(best);
    }
    int value = best * kScale;
    if (j > 0 && j < n - 1) {
        const int before = sum[j - 1];
        const int after = sum[j + 1];
        const int denom = std::max(before + after - 2 * static_cast<int>(minSum), 1);
        value += ((before - after) * kScale + denom) / (denom * 2);
    }
    disp[x] = static_cast<std::int16_t>(value);
}

void CensusSgm::leftRightCheck(std::int16_t* disp) const noexcept
{
    const int maxDiff = config_.disp12MaxDiff;
    if (maxDiff < 0) {
        return;
    }
    const auto inconsistent = [&](int x2, int d) {
        if (x2 < 0 || x2 >= width_) {
            return false;
        }
        const int d2 = disp2_[static_cast<std::size_t>(x2)];
        return d2 >= 0 && std::abs(d2 - d) > maxDiff;
    };
    for (int x = x0_; x < width_; ++x) {
        const int d1 = disp[x];
        if (d1 == kInvalid) {
            continue;
        }
        const int dFloor = d1 >> 4;
        const int dCeil = (d1 + kScale - 1) >> 4;
        if (inconsistent(x - dFloor, dFloor) && inconsistent(x - dCeil, dCeil)) {
            disp[x] = kInvalid;
        }
    }
}

bool CensusSgm::match(ConstImageViewU8 left, ConstImageViewU8 right, cv::Mat& disp16, VisionStageTimes* times) noexcept
{
    const auto sizeOk = [this](ConstImageViewU8 v) {
        return v.data() != nullptr && v.width() == width_ && v.height() == height_;
    };
    if (!sizeOk(left) || !sizeOk(right) || disp16.type() != CV_16SC1 || disp16.cols != width_ ||
        disp16.rows != height_) {
        return false;
    }
    StageLap lap(times);
    census(left, leftCensus_.data(), false);
    census(right, rightCensus_.data(), true);
    std::fill(paths_.begin(), paths_.end(), std::uint8_t{255});
    std::fill(pathMin_.begin(), pathMin_.end(), std::uint8_t{255});
    parity_ = 0;
    searchRanges();
    lap.to(VisionStage::Census);
    for (int y = 0; y < height_; ++y) {
        auto* disp = disp16.ptr<std::int16_t>(y);
        std::fill(disp, disp + x0_, kInvalid);
        costRow(y);
        lap.to(VisionStage::Cost);
        aggregateRow(disp, y > 0 ? disp16.ptr<std::int16_t>(y - 1) : nullptr, y);
        lap.to(VisionStage::Aggregate);
        leftRightCheck(disp);
        lap.to(VisionStage::LeftRight);
    }
    if (config_.speckleWindowSize > 0) {
        try {
            cv::filterSpeckles(disp16, kInvalid, config_.speckleWindowSize, kScale * config_.speckleRange,
                               speckleBuffer_);
        } catch (...) {
            disp16.setTo(kInvalid); // not reachable with the checked sizes; never a half-filtered output
        }
    }
    lap.to(VisionStage::Speckle);
    return true;
}

} // namespace ugv::vision
