#pragma once

/// @file
/// Internal to the simulator: the ground's height field (road with camber and grade, kerb and pavement) with an
/// exact ray intersection, and the ground's look (paint, rails, hard shadows, mirror-like regions).
///
/// Thread-safety: immutable after construction (reentrant). RT-safe: no (host tooling).

#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "ugv/sim/scene.hpp"

namespace ugv::sim::detail {

/// Fraction of [a - w/2, a + w/2] covered by intervals of width `wire` centred at multiples of `spacing`.
double wireCoverage(double a, double w, double spacing, double wire) noexcept;

/// A plane z = c0 + cx x + cy y of the world frame.
struct GroundPlane {
    double c0 = 0.0; ///< [m]
    double cx = 0.0; ///< slope along x
    double cy = 0.0; ///< slope along y
    [[nodiscard]] double at(double x, double y) const noexcept { return c0 + cx * x + cy * y; }
};

enum class GroundPart : std::uint8_t { None, Road, Pavement, KerbFace };

struct GroundHit {
    double t = std::numeric_limits<double>::infinity(); ///< [m] along the unit ray
    GroundPart part = GroundPart::None;
    GroundPlane plane;                ///< the piece of the surface that was hit (road or pavement)
    Eigen::Vector3d n{0.0, 0.0, 1.0}; ///< unit normal
};

/// The height field of a GroundShape: up to 2 x 3 planar pieces (split at the grade line x = gradeAtX and at the
/// crown and kerb lines) and the vertical kerb face. The intersection is exact: the nearest crossing of the ray
/// with any piece inside its own region, or with the kerb face between road and pavement level.
class GroundModel {
public:
    explicit GroundModel(const GroundShape& shape);

    [[nodiscard]] bool flat() const noexcept { return shape_.flat(); }
    /// [m] the road surface (no kerb step) at (x, y).
    [[nodiscard]] double roadHeight(double x, double y) const noexcept;
    /// [m] the ground (road, or pavement beyond the kerb) at (x, y).
    [[nodiscard]] double height(double x, double y) const noexcept;
    /// Upper bound of |dz/dx| + |dz/dy| of the road (how far an obstacle's bottom must reach below its centre).
    [[nodiscard]] double maxSlope() const noexcept;
    /// Nearest hit with t > tMin of the ray from `o` along unit `d`; part None when it misses.
    [[nodiscard]] GroundHit intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMin) const noexcept;

private:
    struct Region {
        double x0 = 0.0; // [m] bounds
        double x1 = 0.0;
        double y0 = 0.0;
        double y1 = 0.0;
        GroundPlane plane;
        GroundPart part = GroundPart::Road;
    };
    [[nodiscard]] bool onPavement(double y) const noexcept;

    GroundShape shape_;
    std::vector<Region> regions_;
};

/// The ground's albedo patterns and mirrors of a Scene (markings, shadows, reflectors).
class GroundLook {
public:
    explicit GroundLook(const Scene& scene);

    /// `albedo` of the bare ground texture at (x, y) with paint, rails and shadows applied; stripes are box-filtered
    /// over `footprint` [m].
    [[nodiscard]] double albedo(double albedo, double x, double y, double footprint) const noexcept;
    /// albedo() in colour: `colour` is the bare texture's albedo times its chroma (B, G, R); paint, rails and shadows
    /// apply as in albedo(), each stripe with its own chroma (white or yellow paint, steel, a dark groove), so that the
    /// luminance of the result is albedo()'s.
    [[nodiscard]] Eigen::Vector3d colour(Eigen::Vector3d colour, double x, double y, double footprint) const noexcept;
    /// Reflectance of the ground at (x, y): the largest of the reflectors containing it, else 0.
    [[nodiscard]] double reflectance(double x, double y) const noexcept;

private:
    struct Stripe {
        double centre = 0.0; // [m] y of a stripe along x, or x of a stripe across
        double width = 0.0;  // [m]
        double albedo = 0.0;
        double period = 0.0; // [m] dash period along x; 0 = solid
        double dash = 0.0;   // [m]
        bool alongX = true;
        Eigen::Vector3d chroma{1.0, 1.0, 1.0}; // B, G, R, luminance 1
    };
    /// Fraction of the footprint around (x, y) that stripe `s` covers.
    [[nodiscard]] static double coverage(const Stripe& s, double x, double y, double footprint) noexcept;
    std::vector<Stripe> stripes_;
    const std::vector<Shadow>& shadows_;
    const std::vector<Reflector>& reflectors_;
};

} // namespace ugv::sim::detail
