#include "ugv/sim/renderer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core/matx.hpp>
#include <opencv2/imgcodecs.hpp>

#include "ugv/platform/angles.hpp"
#include "ugv/sim/ground.hpp"
#include "ugv/sim/noise.hpp"

namespace ugv::sim {
namespace {

using detail::GroundPart;
using detail::Octave;
using detail::wireCoverage;
using Eigen::Vector3d;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTinyDir = 1e-12;     // direction components below this count as parallel
constexpr double kBehindEpsM = 1e-6;   // [m] restart distance behind a partially covering fence
constexpr int kFenceLayers = 3;        // fences a ray may see through
constexpr double kMinIncidence = 0.02; // |cos| floor of the footprint stretch at grazing incidence
constexpr double kAmbient = 0.55;      // Lambert shading: ambient + diffuse * max(0, n.sun)
constexpr double kDiffuse = 0.45;
constexpr double kTableTopThicknessM = 0.04; // [m]
constexpr double kTableLegInsetM = 0.05;     // [m]
constexpr double kFencePostSpacingM = 2.5;   // [m] at most
constexpr double kStripeM = 0.2;             // [m] barrier stripe width
constexpr double kHeightBandM = 0.10;        // [m] sector height: max over hits within this of the nearest
constexpr int kFullScreen = 1 << 20;         // [px] screen rectangle of a primitive behind the camera
constexpr int kMirrorBounces = 1;            // reflections of reflections are not traced
constexpr double kDeepM = 1e3;               // [m] the background wall reaches this far down on a non-flat ground

enum class PrimKind : std::uint8_t { Cylinder, Box, Sphere, Fence };
enum class Surface : std::uint8_t { Sky, Ground, Object, HoleWall, HoleFloor, Background, Kerb };

/// One analytic primitive in world coordinates. Box-like kinds use a local frame centred at (cx, cy) and
/// rotated by yaw; vertical extent [z0, z1] (sphere: centre height z0).
struct Prim {
    PrimKind kind = PrimKind::Box;
    int obstacle = 0;
    double cx = 0.0, cy = 0.0; // [m]
    double cosYaw = 1.0, sinYaw = 0.0;
    double hx = 0.0, hy = 0.0;        // [m] half extents (fence: hx unused, hy half length)
    double z0 = 0.0, z1 = 0.0;        // [m]
    double r = 0.0;                   // [m] cylinder or sphere radius
    double spacing = 0.0, wire = 0.0; // [m] fence grid
};

/// A negative obstacle: footprint (round or yawed rectangle) sunk depth metres below the ground.
struct Neg {
    int obstacle = 0;
    bool round = true;
    double cx = 0.0, cy = 0.0, cosYaw = 1.0, sinYaw = 0.0, hx = 0.0, hy = 0.0, r = 0.0, depth = 0.0; // [m]
};

struct ObjectInfo {
    Label label = Label::Positive;
    double albedo = 0.5;
    Vector3d chroma{1.0, 1.0, 1.0}; ///< B, G, R, luminance 1 (a barrier's dark stripes)
    bool striped = false;
    double depthM = 0.0; ///< [m] a negative obstacle's depth below the ground
};

struct Hit {
    double t = kInf; // [m] along the unit ray
    Vector3d n{0.0, 0.0, 1.0};
    Surface surface = Surface::Sky;
    int prim = -1;
    int obstacle = -1;
    double tGround = kInf; ///< [m] where the ray crossed the ground surface (hole walls and floors)
};

/// Where a ray is traced from: the pixel whose primitives' screen rectangles cull the scene (primary rays only), the
/// fence layers and mirror bounces left, and the path length before this ray (texture footprint).
struct RayContext {
    int px = 0;
    int py = 0;
    int view = 0;
    int layers = kFenceLayers;
    int bounces = kMirrorBounces;
    double pathM = 0.0; ///< [m]
    bool cull = true;
    bool colour = false; ///< also compute the colour (left image only)
};

/// What a ray sees: the grey radiance and, when asked for, its colour (B, G, R) whose luminance is the grey one.
struct Radiance {
    double grey = 0.0;
    Vector3d bgr = Vector3d::Zero();
};

Vector3d toVector(const Chroma& c)
{
    return {c.b, c.g, c.r};
}

struct ScreenRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0; // inclusive [px]
};

/// Local coordinates of (x, y) in a frame centred at (cx, cy), rotated by (c, s).
inline void toLocal(double x, double y, double cx, double cy, double c, double s, double& lx, double& ly) noexcept
{
    const double dx = x - cx;
    const double dy = y - cy;
    lx = c * dx + s * dy;
    ly = -s * dx + c * dy;
}

constexpr std::array<Octave, 6> kAsphalt = {
    {{0.006, 0.35}, {0.015, 0.3}, {0.04, 0.2}, {0.12, 0.12}, {0.5, 0.1}, {2.0, 0.1}}};
constexpr std::array<Octave, 6> kGrass = {
    {{0.008, 0.45}, {0.02, 0.4}, {0.06, 0.2}, {0.3, 0.2}, {1.2, 0.25}, {4.0, 0.2}}};
constexpr std::array<Octave, 5> kGravel = {{{0.01, 0.35}, {0.025, 0.55}, {0.08, 0.15}, {0.4, 0.1}, {2.0, 0.1}}};
constexpr std::array<Octave, 4> kPaint = {{{0.005, 0.2}, {0.05, 0.3}, {0.8, 0.5}, {3.0, 0.5}}};
constexpr std::array<Octave, 5> kObject = {{{0.007, 0.3}, {0.02, 0.35}, {0.06, 0.25}, {0.2, 0.15}, {0.8, 0.1}}};
constexpr std::array<Octave, 4> kSoil = {{{0.01, 0.4}, {0.03, 0.35}, {0.1, 0.2}, {0.4, 0.1}}};
constexpr std::array<Octave, 5> kFar = {{{0.03, 0.3}, {0.1, 0.3}, {0.4, 0.3}, {1.5, 0.2}, {5.0, 0.2}}};

struct GroundStyle {
    std::span<const Octave> octaves;
    double base = 0.35;
    double spread = 0.5;
};

GroundStyle groundStyle(GroundTexture texture) noexcept
{
    switch (texture) {
    case GroundTexture::Grass:
        return {kGrass, 0.38, 0.7};
    case GroundTexture::Gravel:
        return {kGravel, 0.5, 0.9};
    case GroundTexture::PaintedFloor:
        return {kPaint, 0.62, 0.06};
    case GroundTexture::Asphalt:
        break;
    }
    return {kAsphalt, 0.33, 0.75};
}

/// The scene compiled into primitives, plus the cameras of the current pose.
class Tracer {
public:
    Tracer(const Scene& scene, const Pose& pose, const RenderOptions& options)
        : scene_(scene), options_(options), ground_(scene.ground), look_(scene),
          wallBottom_(scene.ground.flat() ? 0.0 : -kDeepM)
    {
        compile();
        setupCameras(pose);
        for (int view = 0; view < 2; ++view) {
            for (const Prim& p : prims_) {
                rects_[static_cast<std::size_t>(view)].push_back(screenRect(p, view));
            }
        }
    }

    Vector3d origin(int view) const { return view == 0 ? originL_ : originL_ + scene_.rig.baselineM * right_; }
    /// Unit ray direction through image point (u, v) [px].
    Vector3d direction(double u, double v) const
    {
        const Rig& rig = scene_.rig;
        return (forward_ + ((u - rig.cx()) / rig.focalPx) * right_ + ((v - rig.cy()) / rig.focalPx) * down_)
            .normalized();
    }
    const Vector3d& forward() const { return forward_; }
    const Vector3d& vehicleOrigin() const { return vehicleOrigin_; }
    double cosYaw() const { return cosYaw_; }
    double sinYaw() const { return sinYaw_; }
    const ObjectInfo& info(int obstacle) const { return infos_[static_cast<std::size_t>(obstacle)]; }
    bool isFence(int prim) const { return prims_[static_cast<std::size_t>(prim)].kind == PrimKind::Fence; }
    /// [m] the ground below a hit point: the road's for the kerb face (its foot), else the local surface's.
    double groundBelow(const Hit& hit, const Vector3d& p) const
    {
        if (ground_.flat()) {
            return 0.0;
        }
        return hit.surface == Surface::Kerb ? ground_.roadHeight(p.x(), p.y()) : ground_.height(p.x(), p.y());
    }
    /// [m] the point where a ray that hit a hole's wall or floor crossed the ground (its near rim).
    Vector3d rim(const Hit& hit, const Vector3d& o, const Vector3d& d, const Vector3d& p) const
    {
        return ground_.flat() ? Vector3d(p - (p.z() / d.z()) * d) : Vector3d(o + hit.tGround * d);
    }

    /// Nearest hit with t > tMin of the ray from `o` along unit `d`, sampled inside pixel (px, py) of `view`;
    /// `cull` = false for secondary rays (reflections), which the screen rectangles do not bound.
    Hit trace(const Vector3d& o, const Vector3d& d, double tMin, int px, int py, int view, bool cull = true) const
    {
        Hit best = traceGround(o, d, tMin);
        traceBackground(o, d, tMin, best);
        const std::vector<ScreenRect>& rects = rects_[static_cast<std::size_t>(view)];
        for (std::size_t i = 0; i < prims_.size(); ++i) {
            const ScreenRect& r = rects[i];
            if (cull && (px < r.x0 || px > r.x1 || py < r.y0 || py > r.y1)) {
                continue;
            }
            intersect(prims_[i], static_cast<int>(i), o, d, tMin, best);
        }
        return best;
    }

    /// Radiance (albedo x shading, before the camera gains) along a ray; fences blend with what lies behind, mirrors
    /// on the ground with what the reflected ray sees. The colour (ray.colour) follows the same blends, so that its
    /// luminance is the grey radiance; the grey arithmetic is the same with or without it.
    // NOLINTNEXTLINE(misc-no-recursion): a ray tracer's, bounded: each call spends one of ray.bounces or ray.layers
    Radiance radiance(const Vector3d& o, const Vector3d& d, double tMin, const RayContext& ray) const
    {
        const Hit hit = trace(o, d, tMin, ray.px, ray.py, ray.view, ray.cull);
        if (hit.surface == Surface::Sky) {
            const double s = sky(d);
            return {s, ray.colour ? Vector3d(s * skyChroma_) : Vector3d::Zero()};
        }
        const Vector3d p = o + hit.t * d;
        // [m] pixel footprint, only mildly stretched at grazing incidence: the across-view detail that stereo
        // matching needs is kept, and the supersampling handles the foreshortened direction.
        const double footprint = (ray.pathM + hit.t) / scene_.rig.focalPx /
                                 std::sqrt(std::sqrt(std::max(std::abs(hit.n.dot(d)), kMinIncidence)));
        Vector3d colour = Vector3d::Zero();
        const double shade = shading(hit.n);
        const double value = albedo(hit, p, footprint, ray.colour ? &colour : nullptr) * shade;
        colour *= shade;
        if (hit.surface == Surface::Ground && ray.bounces > 0) {
            const double reflectance = look_.reflectance(p.x(), p.y());
            if (reflectance > 0.0) {
                RayContext mirrored = ray;
                mirrored.cull = false;
                mirrored.bounces = ray.bounces - 1;
                mirrored.pathM = ray.pathM + hit.t;
                const Vector3d r = d - 2.0 * d.dot(hit.n) * hit.n;
                const Radiance seen = radiance(p, r, kBehindEpsM, mirrored);
                return {(1.0 - reflectance) * value + reflectance * seen.grey,
                        (1.0 - reflectance) * colour + reflectance * seen.bgr};
            }
        }
        if (hit.prim < 0 || !isFence(hit.prim) || ray.layers <= 0) {
            return {value, colour};
        }
        const Prim& f = prims_[static_cast<std::size_t>(hit.prim)];
        double lx = 0.0;
        double ly = 0.0;
        toLocal(p.x(), p.y(), f.cx, f.cy, f.cosYaw, f.sinYaw, lx, ly);
        const double sampleFootprint = hit.t / (scene_.rig.focalPx * options_.samplesPerAxis); // [m]
        const double across = wireCoverage(ly + f.hy, sampleFootprint, f.spacing, f.wire);
        const double up = wireCoverage(p.z() - f.z0, sampleFootprint, f.spacing, f.wire);
        const double coverage = 1.0 - (1.0 - across) * (1.0 - up);
        RayContext behindRay = ray;
        behindRay.layers = ray.layers - 1;
        const Radiance behind = radiance(o, d, hit.t + kBehindEpsM, behindRay);
        return {coverage * value + (1.0 - coverage) * behind.grey, coverage * colour + (1.0 - coverage) * behind.bgr};
    }

private:
    void compile()
    {
        const double clearance = options_.clearanceM;
        for (std::size_t i = 0; i < scene_.obstacles.size(); ++i) {
            const Obstacle& o = scene_.obstacles[i];
            const int id = static_cast<int>(i);
            const auto centre = obstacleCentre(o);
            const double cx = centre.first; // named, not bound: the lambdas below capture them
            const double cy = centre.second;
            const double c = std::cos(o.yawDeg * kDegToRad);
            const double s = std::sin(o.yawDeg * kDegToRad);
            ObjectInfo info;
            info.albedo = o.albedo;
            info.chroma = toVector(o.chroma.value_or(defaultChroma(o.type)));
            info.striped = o.type == ObstacleType::Barrier;
            // The object stands on the ground at its footprint centre; parts that touch the ground reach `sink`
            // below it, so that no gap opens under them where the ground falls away (the ground hides the rest).
            const double base = ground_.height(cx, cy);                                                   // [m]
            const double sink = ground_.maxSlope() * (std::hypot(o.lengthM, o.widthM) / 2.0 + o.radiusM); // [m]
            const auto bottom = [&](double z0) { return z0 > 0.0 ? base + z0 : base - sink; };
            // Local point (lx, ly) of this object's frame in world coordinates.
            const auto wx = [&](double lx, double ly) { return cx + c * lx - s * ly; };
            const auto wy = [&](double lx, double ly) { return cy + s * lx + c * ly; };
            const auto addBox = [&](double lx, double ly, double hx, double hy, double z0, double z1) {
                Prim p;
                p.kind = PrimKind::Box;
                p.obstacle = id;
                p.cx = wx(lx, ly);
                p.cy = wy(lx, ly);
                p.cosYaw = c;
                p.sinYaw = s;
                p.hx = hx;
                p.hy = hy;
                p.z0 = bottom(z0);
                p.z1 = base + z1;
                prims_.push_back(p);
            };
            const auto addCylinder = [&](double lx, double ly, double r, double z0, double z1) {
                Prim p;
                p.kind = PrimKind::Cylinder;
                p.obstacle = id;
                p.cx = wx(lx, ly);
                p.cy = wy(lx, ly);
                p.r = r;
                p.z0 = bottom(z0);
                p.z1 = base + z1;
                prims_.push_back(p);
            };
            switch (o.type) {
            case ObstacleType::Pole:
                addCylinder(0.0, 0.0, o.radiusM, 0.0, o.heightM);
                break;
            case ObstacleType::TableLegs: {
                const double top0 = o.heightM - kTableTopThicknessM;
                addBox(0.0, 0.0, o.lengthM / 2.0, o.widthM / 2.0, top0, o.heightM);
                const double lx = o.lengthM / 2.0 - kTableLegInsetM;
                const double ly = o.widthM / 2.0 - kTableLegInsetM;
                for (const double sx : {-1.0, 1.0}) {
                    for (const double sy : {-1.0, 1.0}) {
                        addCylinder(sx * lx, sy * ly, o.radiusM, 0.0, top0);
                    }
                }
                break;
            }
            case ObstacleType::Box:
            case ObstacleType::Barrier:
            case ObstacleType::Curb:
                addBox(0.0, 0.0, o.lengthM / 2.0, o.widthM / 2.0, 0.0, o.heightM);
                break;
            case ObstacleType::Overhang:
                info.label = o.elevationM > clearance ? Label::Overhang : Label::Positive;
                addBox(0.0, 0.0, o.lengthM / 2.0, o.widthM / 2.0, o.elevationM, o.heightM);
                break;
            case ObstacleType::WallWithDoorway: {
                const double segment = (o.widthM - o.gapM) / 2.0;
                for (const double side : {-1.0, 1.0}) {
                    addBox(0.0, side * (o.gapM + segment) / 2.0, o.lengthM / 2.0, segment / 2.0, 0.0, o.heightM);
                }
                break;
            }
            case ObstacleType::MeshFence: {
                Prim p;
                p.kind = PrimKind::Fence;
                p.obstacle = id;
                p.cx = cx;
                p.cy = cy;
                p.cosYaw = c;
                p.sinYaw = s;
                p.hy = o.widthM / 2.0;
                p.z0 = bottom(0.0);
                p.z1 = base + o.heightM;
                p.spacing = o.spacingM;
                p.wire = o.wireM;
                prims_.push_back(p);
                const int posts = std::max(2, static_cast<int>(std::ceil(o.widthM / kFencePostSpacingM)) + 1);
                for (int k = 0; k < posts; ++k) {
                    const double ly = -o.widthM / 2.0 + o.widthM * k / (posts - 1);
                    // Posts stand behind the wire plane, tangent to it: the plane is the nearest surface.
                    addCylinder(o.radiusM, ly, o.radiusM, 0.0, o.heightM + o.radiusM);
                }
                break;
            }
            case ObstacleType::Person: {
                const double k = o.heightM / 1.7; // body proportions for 1.7 m
                for (const double side : {-1.0, 1.0}) {
                    addCylinder(0.0, side * 0.1 * k, 0.07 * k, 0.0, 0.85 * k);       // leg
                    addCylinder(0.0, side * 0.27 * k, 0.045 * k, 0.8 * k, 1.42 * k); // arm
                }
                addBox(0.0, 0.0, o.lengthM / 2.0, 0.2 * k, 0.85 * k, 1.45 * k); // torso
                addCylinder(0.0, 0.0, 0.05 * k, 1.45 * k, 1.5 * k);             // neck
                Prim head;
                head.kind = PrimKind::Sphere;
                head.obstacle = id;
                head.cx = cx;
                head.cy = cy;
                head.r = 0.11 * k;
                head.z0 = base + o.heightM - head.r;
                prims_.push_back(head);
                break;
            }
            case ObstacleType::Trench:
            case ObstacleType::Hole: {
                info.label = Label::Negative;
                info.depthM = o.depthM;
                Neg n;
                n.obstacle = id;
                n.round = o.type == ObstacleType::Hole && o.round;
                n.cx = cx;
                n.cy = cy;
                n.cosYaw = c;
                n.sinYaw = s;
                n.hx = o.lengthM / 2.0;
                n.hy = o.widthM / 2.0;
                if (o.type == ObstacleType::Hole && !o.round) {
                    n.hx = o.widthM / 2.0;
                }
                n.r = o.radiusM;
                n.depth = o.depthM;
                negs_.push_back(n);
                break;
            }
            }
            infos_.push_back(info);
        }
    }

    void setupCameras(const Pose& pose)
    {
        const Rig& rig = scene_.rig;
        const double p = rig.pitchDeg * kDegToRad;
        const double r = rig.rollDeg * kDegToRad;
        // Vehicle frame (x forward, y left, z up): optical axis pitched down by p, then rolled about it.
        const Vector3d f(std::cos(p), 0.0, -std::sin(p));
        const Vector3d right0(0.0, -1.0, 0.0);
        const Vector3d down0 = f.cross(right0);
        const Vector3d rightV = std::cos(r) * right0 + std::sin(r) * down0;
        const Vector3d downV = -std::sin(r) * right0 + std::cos(r) * down0;
        cosYaw_ = std::cos(pose.yawDeg * kDegToRad);
        sinYaw_ = std::sin(pose.yawDeg * kDegToRad);
        const auto rotate = [&](const Vector3d& v) {
            return Vector3d(cosYaw_ * v.x() - sinYaw_ * v.y(), sinYaw_ * v.x() + cosYaw_ * v.y(), v.z());
        };
        forward_ = rotate(f);
        right_ = rotate(rightV);
        down_ = rotate(downV);
        vehicleOrigin_ = Vector3d(pose.x, pose.y, 0.0);
        originL_ = vehicleOrigin_ + Vector3d(0.0, 0.0, rig.heightM);
    }

    /// Image rectangle that contains every pixel whose rays can hit `p` (projected bounding box + 2 px).
    ScreenRect screenRect(const Prim& p, int view) const
    {
        double ex = p.r;
        double ey = p.r;
        double z0 = p.z0;
        double z1 = p.z1;
        if (p.kind == PrimKind::Box || p.kind == PrimKind::Fence) {
            const double hx = p.kind == PrimKind::Fence ? p.wire : p.hx;
            ex = std::abs(p.cosYaw) * hx + std::abs(p.sinYaw) * p.hy;
            ey = std::abs(p.sinYaw) * hx + std::abs(p.cosYaw) * p.hy;
        } else if (p.kind == PrimKind::Sphere) {
            z0 = p.z0 - p.r;
            z1 = p.z0 + p.r;
        }
        const Rig& rig = scene_.rig;
        const Vector3d o = origin(view);
        double u0 = kInf, v0 = kInf, u1 = -kInf, v1 = -kInf;
        for (int corner = 0; corner < 8; ++corner) {
            const Vector3d q(p.cx + ((corner & 1) != 0 ? ex : -ex), p.cy + ((corner & 2) != 0 ? ey : -ey),
                             (corner & 4) != 0 ? z1 : z0);
            const Vector3d rel = q - o;
            const double z = rel.dot(forward_);
            if (z < 1e-3) {
                return ScreenRect{-kFullScreen, -kFullScreen, kFullScreen, kFullScreen};
            }
            const double u = rig.cx() + rig.focalPx * rel.dot(right_) / z;
            const double v = rig.cy() + rig.focalPx * rel.dot(down_) / z;
            u0 = std::min(u0, u);
            u1 = std::max(u1, u);
            v0 = std::min(v0, v);
            v1 = std::max(v1, v);
        }
        const auto clampPx = [](double x) { return static_cast<int>(std::clamp(x, -1e6, 1e6)); };
        return ScreenRect{clampPx(std::floor(u0)) - 2, clampPx(std::floor(v0)) - 2, clampPx(std::ceil(u1)) + 2,
                          clampPx(std::ceil(v1)) + 2};
    }

    /// The ground, or the wall or floor of the negative obstacle whose footprint the ray enters.
    Hit traceGround(const Vector3d& o, const Vector3d& d, double tMin) const
    {
        if (!ground_.flat()) {
            return traceShapedGround(o, d, tMin);
        }
        Hit hit;
        if (d.z() > -kTinyDir) {
            return hit;
        }
        const double tg = -o.z() / d.z();
        const double gx = o.x() + tg * d.x();
        const double gy = o.y() + tg * d.y();
        for (const Neg& n : negs_) {
            double lx = 0.0;
            double ly = 0.0;
            if (contains(n, gx, gy, lx, ly)) {
                return intoNegative(n, o, d, tMin, tg, lx, ly, (-n.depth - o.z()) / d.z());
            }
        }
        if (tg > tMin) {
            hit.t = tg;
            hit.surface = Surface::Ground;
        }
        return hit;
    }

    /// traceGround() on a height field: road, pavement or kerb face; a hole's floor lies `depth` below the piece of
    /// the ground the ray entered through, parallel to it.
    Hit traceShapedGround(const Vector3d& o, const Vector3d& d, double tMin) const
    {
        const detail::GroundHit g = ground_.intersect(o, d, tMin);
        Hit hit;
        if (g.part == GroundPart::None) {
            return hit;
        }
        hit.t = g.t;
        hit.n = g.n;
        hit.surface = g.part == GroundPart::KerbFace ? Surface::Kerb : Surface::Ground;
        if (g.part == GroundPart::KerbFace || d.z() > -kTinyDir) {
            return hit;
        }
        const double gx = o.x() + g.t * d.x();
        const double gy = o.y() + g.t * d.y();
        for (const Neg& n : negs_) {
            double lx = 0.0;
            double ly = 0.0;
            if (contains(n, gx, gy, lx, ly)) {
                const detail::GroundPlane& plane = g.plane;
                const double tFloor =
                    (plane.at(o.x(), o.y()) - n.depth - o.z()) / (d.z() - plane.cx * d.x() - plane.cy * d.y());
                Hit inside = intoNegative(n, o, d, tMin, g.t, lx, ly, tFloor);
                inside.tGround = g.t;
                return inside;
            }
        }
        return hit;
    }

    /// Whether the ground point (x, y) lies in the footprint of `n`; (lx, ly) its local coordinates.
    static bool contains(const Neg& n, double x, double y, double& lx, double& ly)
    {
        toLocal(x, y, n.cx, n.cy, n.cosYaw, n.sinYaw, lx, ly);
        return n.round ? lx * lx + ly * ly < n.r * n.r : std::abs(lx) < n.hx && std::abs(ly) < n.hy;
    }

    /// The wall or floor of `n` hit by a ray that entered its footprint at tg (local (lx, ly)); the floor at tFloor.
    static Hit intoNegative(const Neg& n, const Vector3d& o, const Vector3d& d, double tMin, double tg, double lx,
                            double ly, double tFloor)
    {
        Hit hit;
        double tWall = kInf;
        Vector3d wallNormal(0.0, 0.0, 1.0);
        if (n.round) {
            const double ox = o.x() - n.cx;
            const double oy = o.y() - n.cy;
            const double a = d.x() * d.x() + d.y() * d.y();
            if (a > kTinyDir) {
                const double b = ox * d.x() + oy * d.y();
                const double c = ox * ox + oy * oy - n.r * n.r;
                const double disc = std::max(b * b - a * c, 0.0);
                tWall = (-b + std::sqrt(disc)) / a;
                wallNormal = Vector3d(-(ox + tWall * d.x()), -(oy + tWall * d.y()), 0.0) / n.r;
            }
        } else {
            const double ldx = n.cosYaw * d.x() + n.sinYaw * d.y();
            const double ldy = -n.sinYaw * d.x() + n.cosYaw * d.y();
            // Exit through the far slab in x and y; the inward normal faces back along the ray.
            if (std::abs(ldx) > kTinyDir) {
                const double t = tg + ((ldx > 0.0 ? n.hx : -n.hx) - lx) / ldx;
                if (t < tWall) {
                    tWall = t;
                    const double sx = ldx > 0.0 ? -1.0 : 1.0;
                    wallNormal = Vector3d(sx * n.cosYaw, sx * n.sinYaw, 0.0);
                }
            }
            if (std::abs(ldy) > kTinyDir) {
                const double t = tg + ((ldy > 0.0 ? n.hy : -n.hy) - ly) / ldy;
                if (t < tWall) {
                    tWall = t;
                    const double sy = ldy > 0.0 ? -1.0 : 1.0;
                    wallNormal = Vector3d(-sy * n.sinYaw, sy * n.cosYaw, 0.0);
                }
            }
        }
        hit.obstacle = n.obstacle;
        if (tFloor <= tWall) {
            hit.t = tFloor;
            hit.surface = Surface::HoleFloor;
            hit.n = Vector3d(0.0, 0.0, 1.0);
        } else {
            hit.t = tWall;
            hit.surface = Surface::HoleWall;
            hit.n = wallNormal;
        }
        return hit.t > tMin ? hit : Hit{};
    }

    void traceBackground(const Vector3d& o, const Vector3d& d, double tMin, Hit& best) const
    {
        const Background& bg = scene_.background;
        if (bg.type != BackgroundType::Walls) {
            return;
        }
        const double a = d.x() * d.x() + d.y() * d.y();
        if (a < kTinyDir) {
            return;
        }
        const double b = o.x() * d.x() + o.y() * d.y();
        const double c = o.x() * o.x() + o.y() * o.y() - bg.wallDistanceM * bg.wallDistanceM;
        const double disc = b * b - a * c;
        if (disc < 0.0) {
            return;
        }
        const double s = std::sqrt(disc);
        const double t = c < 0.0 ? (-b + s) / a : (-b - s) / a;
        const double z = o.z() + t * d.z();
        if (t > tMin && t < best.t && z >= wallBottom_ && z <= bg.wallHeightM) {
            best.t = t;
            best.surface = Surface::Background;
            best.n = Vector3d(-(o.x() + t * d.x()), -(o.y() + t * d.y()), 0.0) / bg.wallDistanceM;
            best.obstacle = -1;
            best.prim = -1;
        }
    }

    static void accept(Hit& best, double t, const Vector3d& n, int prim, int obstacle)
    {
        best.t = t;
        best.n = n;
        best.surface = Surface::Object;
        best.prim = prim;
        best.obstacle = obstacle;
    }

    static void intersect(const Prim& p, int index, const Vector3d& o, const Vector3d& d, double tMin, Hit& best)
    {
        switch (p.kind) {
        case PrimKind::Cylinder: {
            const double ox = o.x() - p.cx;
            const double oy = o.y() - p.cy;
            const double a = d.x() * d.x() + d.y() * d.y();
            if (a > kTinyDir) {
                const double b = ox * d.x() + oy * d.y();
                const double c = ox * ox + oy * oy - p.r * p.r;
                const double disc = b * b - a * c;
                if (disc >= 0.0) {
                    const double t = (-b - std::sqrt(disc)) / a;
                    const double z = o.z() + t * d.z();
                    if (t > tMin && t < best.t && z >= p.z0 && z <= p.z1) {
                        accept(best, t, Vector3d(ox + t * d.x(), oy + t * d.y(), 0.0) / p.r, index, p.obstacle);
                    }
                }
            }
            if (d.z() < -kTinyDir) { // top cap, seen from above
                const double t = (p.z1 - o.z()) / d.z();
                const double x = ox + t * d.x();
                const double y = oy + t * d.y();
                if (t > tMin && t < best.t && x * x + y * y <= p.r * p.r) {
                    accept(best, t, Vector3d(0.0, 0.0, 1.0), index, p.obstacle);
                }
            }
            return;
        }
        case PrimKind::Sphere: {
            const Vector3d oc = o - Vector3d(p.cx, p.cy, p.z0);
            const double b = oc.dot(d);
            const double disc = b * b - (oc.squaredNorm() - p.r * p.r);
            if (disc >= 0.0) {
                const double t = -b - std::sqrt(disc);
                if (t > tMin && t < best.t) {
                    accept(best, t, (oc + t * d) / p.r, index, p.obstacle);
                }
            }
            return;
        }
        case PrimKind::Box:
        case PrimKind::Fence:
            break;
        }
        double lx = 0.0;
        double ly = 0.0;
        toLocal(o.x(), o.y(), p.cx, p.cy, p.cosYaw, p.sinYaw, lx, ly);
        const double ldx = p.cosYaw * d.x() + p.sinYaw * d.y();
        const double ldy = -p.sinYaw * d.x() + p.cosYaw * d.y();
        const auto toWorld = [&](double nx, double ny, double nz) {
            return Vector3d(p.cosYaw * nx - p.sinYaw * ny, p.sinYaw * nx + p.cosYaw * ny, nz);
        };
        if (p.kind == PrimKind::Fence) { // the wire plane lx = 0
            if (std::abs(ldx) < kTinyDir) {
                return;
            }
            const double t = -lx / ldx;
            const double y = ly + t * ldy;
            const double z = o.z() + t * d.z();
            if (t > tMin && t < best.t && std::abs(y) <= p.hy && z >= p.z0 && z <= p.z1) {
                accept(best, t, toWorld(ldx > 0.0 ? -1.0 : 1.0, 0.0, 0.0), index, p.obstacle);
            }
            return;
        }
        // Slab test in the box frame; remember which slab the ray enters through for the normal.
        const std::array<double, 3> org = {lx, ly, o.z() - (p.z0 + p.z1) / 2.0};
        const std::array<double, 3> dir = {ldx, ldy, d.z()};
        const std::array<double, 3> half = {p.hx, p.hy, (p.z1 - p.z0) / 2.0};
        double tNear = -kInf;
        double tFar = kInf;
        int axis = -1;
        double sign = 1.0;
        for (std::size_t k = 0; k < 3; ++k) {
            if (std::abs(dir[k]) < kTinyDir) {
                if (std::abs(org[k]) > half[k]) {
                    return;
                }
                continue;
            }
            double t0 = (-half[k] - org[k]) / dir[k];
            double t1 = (half[k] - org[k]) / dir[k];
            const double s = dir[k] > 0.0 ? -1.0 : 1.0;
            if (t0 > t1) {
                std::swap(t0, t1);
            }
            if (t0 > tNear) {
                tNear = t0;
                axis = static_cast<int>(k);
                sign = s;
            }
            tFar = std::min(tFar, t1);
        }
        if (axis < 0 || tNear > tFar || tNear <= tMin || tNear >= best.t) {
            return;
        }
        const Vector3d n =
            axis == 0 ? toWorld(sign, 0.0, 0.0) : (axis == 1 ? toWorld(0.0, sign, 0.0) : Vector3d(0.0, 0.0, sign));
        accept(best, tNear, n, index, p.obstacle);
    }

    static double sky(const Vector3d& d)
    {
        constexpr double kHorizon = 0.80;
        constexpr double kZenithGain = 0.15;
        return std::min(kHorizon + kZenithGain * std::max(d.z(), 0.0), 1.0);
    }

    static double shading(const Vector3d& n)
    {
        static const Vector3d kSun = Vector3d(0.4, 0.3, 0.85).normalized();
        return kAmbient + kDiffuse * std::max(n.dot(kSun), 0.0);
    }

    /// Albedo of the hit surface at p; with `colour`, also its colour (albedo times the surface's chroma).
    double albedo(const Hit& hit, const Vector3d& p, double footprint, Vector3d* colour) const
    {
        constexpr std::uint32_t kGroundSeed = 101U;
        constexpr std::uint32_t kObjectSeed = 202U;
        constexpr std::uint32_t kSoilSeed = 303U;
        constexpr std::uint32_t kFarSeed = 404U;
        constexpr double kMinAlbedo = 0.02;
        // The colour: the albedo times the surface's chroma (a surface of one colour), or for the ground the same
        // mixing of paint and shadows on colours.
        const auto tinted = [colour](double a, const Vector3d& chroma) {
            if (colour != nullptr) {
                *colour = a * chroma;
            }
            return a;
        };
        switch (hit.surface) {
        case Surface::Ground: {
            const GroundStyle g = groundStyle(scene_.texture);
            const double v = g.base + g.spread * detail::fbm2(p.x(), p.y(), g.octaves, footprint, kGroundSeed);
            if (colour != nullptr) {
                *colour = look_.colour(std::clamp(v, kMinAlbedo, 1.0) * groundChromaAt(p, footprint), p.x(), p.y(),
                                       footprint);
            }
            return look_.albedo(std::clamp(v, kMinAlbedo, 1.0), p.x(), p.y(), footprint);
        }
        case Surface::Kerb: { // kerb stones: concrete, like the curb obstacle
            constexpr double kKerbAlbedo = 0.65;
            constexpr std::uint32_t kKerbSeed = 505U;
            const double v = kKerbAlbedo + 0.6 * detail::fbm3(p.x(), p.y(), p.z(), kObject, footprint, kKerbSeed);
            return tinted(std::clamp(v, kMinAlbedo, 1.0), concreteChroma_);
        }
        case Surface::HoleWall:
        case Surface::HoleFloor: {
            // Darker soil; the floor darker still (less sky visible from inside).
            const double occlusion = hit.surface == Surface::HoleFloor ? 0.6 : 0.8;
            const double v = 0.35 + 0.5 * detail::fbm3(p.x(), p.y(), p.z(), kSoil, footprint, kSoilSeed);
            return tinted(std::clamp(v * occlusion, kMinAlbedo, 1.0), info(hit.obstacle).chroma);
        }
        case Surface::Background: {
            const double v = 0.45 + 0.5 * detail::fbm3(p.x(), p.y(), p.z(), kFar, footprint, kFarSeed);
            return tinted(std::clamp(v, kMinAlbedo, 1.0), backgroundChroma_);
        }
        case Surface::Object:
            break;
        case Surface::Sky:
            return 0.0;
        }
        const ObjectInfo& info = infos_[static_cast<std::size_t>(hit.obstacle)];
        const auto seed = kObjectSeed + static_cast<std::uint32_t>(hit.obstacle) * 17U;
        const double n = detail::fbm3(p.x(), p.y(), p.z(), kObject, footprint, seed);
        if (info.striped) {
            const Prim& b = prims_[static_cast<std::size_t>(hit.prim)];
            double lx = 0.0;
            double ly = 0.0;
            toLocal(p.x(), p.y(), b.cx, b.cy, b.cosYaw, b.sinYaw, lx, ly);
            const bool light = static_cast<std::int64_t>(std::floor((ly + p.z()) / kStripeM)) % 2 == 0;
            return tinted(std::clamp((light ? 0.8 : 0.25) + 0.3 * n, kMinAlbedo, 1.0),
                          light ? Vector3d(1.0, 1.0, 1.0) : info.chroma);
        }
        return tinted(std::clamp(info.albedo + 0.6 * n, kMinAlbedo, 1.0), info.chroma);
    }

    /// The ground texture's chroma at p: grass drifts between lush and dry over metres, the others are uniform.
    Vector3d groundChromaAt(const Vector3d& p, double footprint) const
    {
        if (scene_.texture != GroundTexture::Grass) {
            return groundChroma_;
        }
        constexpr std::array<Octave, 2> kHue = {{{0.6, 0.5}, {2.5, 0.7}}};
        constexpr std::uint32_t kHueSeed = 606U;
        constexpr double kHueGain = 0.9;
        const std::uint32_t seed = kHueSeed + scene_.colourSeed * 7919U;
        const double dry = std::clamp(0.5 + kHueGain * detail::fbm2(p.x(), p.y(), kHue, footprint, seed), 0.0, 1.0);
        return (1.0 - dry) * lushGrass_ + dry * dryGrass_;
    }

    const Scene& scene_;
    const RenderOptions& options_;
    detail::GroundModel ground_;
    detail::GroundLook look_;
    double wallBottom_; // [m]
    std::vector<Prim> prims_;
    std::vector<Neg> negs_;
    std::vector<ObjectInfo> infos_;
    std::array<std::vector<ScreenRect>, 2> rects_;
    // Chromas of the colour image (B, G, R, luminance 1); the reference colours are in bringup/sim/README.md.
    Vector3d groundChroma_ = toVector(groundChroma(scene_.texture));
    Vector3d lushGrass_ = toVector(chromaOf(40.0, 120.0, 60.0));
    Vector3d dryGrass_ = toVector(chromaOf(50.0, 115.0, 100.0));
    Vector3d concreteChroma_ = toVector(defaultChroma(ObstacleType::Curb));
    Vector3d backgroundChroma_ = toVector(chromaOf(100.0, 110.0, 140.0)); // buildings: brick and render
    Vector3d skyChroma_ = toVector(chromaOf(235.0, 215.0, 190.0));        // hazy blue
    Vector3d forward_, right_, down_, originL_, vehicleOrigin_;
    double cosYaw_ = 1.0;
    double sinYaw_ = 0.0;
};

/// One qualifying ROI hit for the sectors.
struct SectorHit {
    int sector = 0;
    float rangeM = 0.0F;  // [m]
    float heightM = 0.0F; // [m] height (positive) or depth (negative)
    ObstacleKind kind = ObstacleKind::None;
};

Result<void, Error> validateOptions(const RenderOptions& o)
{
    const bool ok = o.samplesPerAxis >= 1 && o.samplesPerAxis <= 4 && o.roiTopFraction >= 0.0 &&
                    o.roiTopFraction < 1.0 && o.minHeightM >= 0.0 && o.minDepthM >= 0.0 && o.minVisibleDropM >= 0.0 &&
                    o.clearanceM > 0.0 && o.sectorCount >= 1 && o.sectorCount <= kMaxSectors &&
                    o.dangerDistanceM >= 0.0F && o.cautionDistanceM >= o.dangerDistanceM && o.threads >= 0 &&
                    o.threads <= 64;
    if (!ok) {
        return Unexpected(Error{"sim render options", "out of range",
                                "samplesPerAxis 1..4, roiTopFraction [0,1), sectorCount 1.." +
                                    std::to_string(kMaxSectors) + ", caution >= danger >= 0, threads 0..64"});
    }
    return {};
}

using SectorFlags = std::array<bool, kMaxSectors>;

void finishSectors(const std::vector<SectorHit>& hits, const SectorFlags& seesGround, const RenderOptions& options,
                   ObstacleSectors& out)
{
    std::array<float, kMaxSectors> nearest{};
    nearest.fill(std::numeric_limits<float>::infinity());
    std::array<ObstacleKind, kMaxSectors> kinds{};
    for (const SectorHit& h : hits) {
        const auto s = static_cast<std::size_t>(h.sector);
        if (h.rangeM < nearest[s]) {
            nearest[s] = h.rangeM;
            kinds[s] = h.kind;
        }
    }
    std::array<float, kMaxSectors> heights{};
    for (const SectorHit& h : hits) {
        const auto s = static_cast<std::size_t>(h.sector);
        if (h.kind == kinds[s] && h.rangeM <= nearest[s] + static_cast<float>(kHeightBandM)) {
            heights[s] = std::max(heights[s], h.heightM);
        }
    }
    for (std::size_t s = 0; s < static_cast<std::size_t>(out.count); ++s) {
        Sector& sector = out.sectors[s];
        if (std::isfinite(nearest[s])) {
            sector.state = SectorState::Obstacle;
            sector.rangeM = nearest[s];
            sector.kind = kinds[s];
            sector.heightM = heights[s];
            sector.confidence = 1.0F;
        } else if (seesGround[s]) {
            sector.state = SectorState::Clear;
            sector.confidence = 1.0F;
        }
        sector.danger = classify(sector.state, sector.rangeM, options.dangerDistanceM, options.cautionDistanceM);
    }
}

/// The ground-truth sectors being collected: the qualifying hits and the sectors that see free ground.
struct SectorCollector {
    std::vector<SectorHit> hits;
    SectorFlags seesGround{};
    float sectorMin = 0.0F;   // [deg]
    float sectorWidth = 0.0F; // [deg]
    int count = 0;
};

/// Adds the ROI hit at p (label l, `above` [m] over the ground below it) of the left ray `d` to the sectors.
void collectSectorHit(const Tracer& tracer, const RenderOptions& options, const Hit& hit, const Vector3d& d,
                      const Vector3d& p, Label l, double above, SectorCollector& sectors)
{
    // Bearing and range in the vehicle frame.
    const Vector3d rel = p - tracer.vehicleOrigin();
    const double vx = tracer.cosYaw() * rel.x() + tracer.sinYaw() * rel.y();
    const double vy = -tracer.sinYaw() * rel.x() + tracer.cosYaw() * rel.y();
    const auto bearing = static_cast<float>(std::atan2(vy, vx) * kRadToDeg);
    const int sector = static_cast<int>(std::floor((bearing - sectors.sectorMin) / sectors.sectorWidth));
    if (sector < 0 || sector >= sectors.count) {
        return;
    }
    const bool positive = l == Label::Positive && above > options.minHeightM;
    // A drop qualifies by its own depth, wherever it is seen: beyond a few metres only the top of its far
    // wall is in view, a few centimetres below the ground, yet the vehicle must not drive into it.
    const bool negative = l == Label::Negative && tracer.info(hit.obstacle).depthM > options.minDepthM &&
                          -above > options.minVisibleDropM;
    if (!positive && !negative) {
        sectors.seesGround[static_cast<std::size_t>(sector)] = true;
        return;
    }
    // A drop's range is where the ground ends along this bearing: the point where the ray that sees
    // the drop crosses the ground (the near rim), not the far wall or floor it hits behind it.
    double range = std::hypot(vx, vy);
    if (negative && d.z() < 0.0) {
        const Vector3d rim = tracer.rim(hit, tracer.origin(0), d, p) - tracer.vehicleOrigin();
        range = std::hypot(tracer.cosYaw() * rim.x() + tracer.sinYaw() * rim.y(),
                           -tracer.sinYaw() * rim.x() + tracer.cosYaw() * rim.y());
    }
    sectors.hits.push_back(SectorHit{sector, static_cast<float>(range), static_cast<float>(std::abs(above)),
                                     positive ? ObstacleKind::Positive : ObstacleKind::Negative});
}

/// Ground truth: one ray through each left pixel centre; then the sectors.
void renderTruth(const Tracer& tracer, const Scene& scene, const RenderOptions& options, RenderResult& out)
{
    const Rig& rig = scene.rig;
    out.disparity.create(rig.height, rig.width, CV_32F);
    out.depth.create(rig.height, rig.width, CV_32F);
    out.labels.create(rig.height, rig.width, CV_8U);
    out.ids.create(rig.height, rig.width, CV_16U);
    out.height.create(rig.height, rig.width, CV_32F);
    initSectors(out.sectors, options.sectorCount, static_cast<float>(rig.hfovDeg()));
    SectorCollector sectors;
    sectors.sectorMin = out.sectors.sectors[0].bearingMinDeg;
    sectors.sectorWidth = static_cast<float>(rig.hfovDeg()) / static_cast<float>(out.sectors.count);
    sectors.count = out.sectors.count;
    const int roiTop = static_cast<int>(std::floor(options.roiTopFraction * rig.height));
    const auto kerbId = static_cast<std::uint16_t>(scene.obstacles.size() + 1);
    const Vector3d oL = tracer.origin(0);
    for (int y = 0; y < rig.height; ++y) {
        auto* disp = out.disparity.ptr<float>(y);
        auto* depth = out.depth.ptr<float>(y);
        auto* label = out.labels.ptr<std::uint8_t>(y);
        auto* id = out.ids.ptr<std::uint16_t>(y);
        auto* height = out.height.ptr<float>(y);
        for (int x = 0; x < rig.width; ++x) {
            const Vector3d d = tracer.direction(x, y);
            const Hit hit = tracer.trace(oL, d, 0.0, x, y, 0);
            if (hit.surface == Surface::Sky) {
                disp[x] = 0.0F;
                depth[x] = std::numeric_limits<float>::infinity();
                label[x] = static_cast<std::uint8_t>(Label::Far);
                id[x] = 0;
                height[x] = std::numeric_limits<float>::quiet_NaN();
                continue;
            }
            const Vector3d p = oL + hit.t * d;
            const double z = hit.t * d.dot(tracer.forward());        // [m] along the optical axis
            const double above = p.z() - tracer.groundBelow(hit, p); // [m]
            disp[x] = static_cast<float>(rig.focalPx * rig.baselineM / z);
            depth[x] = static_cast<float>(z);
            height[x] = static_cast<float>(above);
            Label l = Label::Ground;
            id[x] = hit.obstacle >= 0 ? static_cast<std::uint16_t>(hit.obstacle + 1) : std::uint16_t{0};
            if (hit.surface == Surface::Background) {
                l = Label::Far;
            } else if (hit.surface == Surface::Kerb) {
                l = Label::Positive;
                id[x] = kerbId;
            } else if (hit.obstacle >= 0) {
                l = tracer.info(hit.obstacle).label;
            }
            label[x] = static_cast<std::uint8_t>(l);
            if (y >= roiTop && l != Label::Far) {
                collectSectorHit(tracer, options, hit, d, p, l, above, sectors);
            }
        }
    }
    finishSectors(sectors.hits, sectors.seesGround, options, out.sectors);
}

/// JPEG round trip of an 8-bit grey or BGR image at `quality` (1..100).
void compressJpeg(cv::Mat& image, int quality)
{
    std::vector<std::uint8_t> bytes;
    cv::imencode(".jpg", image, bytes, {cv::IMWRITE_JPEG_QUALITY, quality});
    image = cv::imdecode(bytes, image.channels() == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
}

/// BT.601 luminance weights of B, G, R (OpenCV's BGR2GRAY).
// NOLINTNEXTLINE(cert-err58-cpp): a fixed-size Eigen vector neither allocates nor throws
const Vector3d kLuma(0.114, 0.587, 0.299);

/// Runs rowBody(y) for every y in [0, rows), the rows dealt out in turn to `threads` threads (this one too; 0: one
/// per core), all joined before it returns. Plain threads, not OpenCV's pool: Debian's OpenCV runs its pool on TBB,
/// whose hand-offs ThreadSanitizer cannot see.
template <typename RowBody>
void forEachRow(int rows, int threads, const RowBody& rowBody)
{
    if (threads <= 0) {
        threads = static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1U, 64U));
    }
    const auto share = [&](int first) {
        for (int y = first; y < rows; y += threads) {
            rowBody(y);
        }
    };
    std::vector<std::jthread> workers; // joined when they go, also when starting one more throws
    workers.reserve(static_cast<std::size_t>(threads - 1));
    for (int k = 1; k < threads; ++k) {
        workers.emplace_back(share, k);
    }
    share(0);
}

/// Each pixel's sums over its samplesPerAxis^2 stratified, jittered rays (grey, and BGR when `colour`), rows in
/// parallel (forEachRow): every pixel is traced alone and the rays are deterministic (lattice jitter, no random draws),
/// so the sums are the same for any number of threads.
void traceView(const Tracer& tracer, const Scene& scene, const RenderOptions& options, int view, bool colour,
               cv::Mat& greySums, cv::Mat& colourSums)
{
    const Rig& rig = scene.rig;
    const int n = options.samplesPerAxis;
    const Vector3d o = tracer.origin(view);
    const auto jitterSeed = static_cast<std::uint32_t>(scene.seed * 7919U + static_cast<std::uint64_t>(view));
    greySums.create(rig.height, rig.width, CV_64F);
    colourSums.create(rig.height, rig.width, CV_64FC3);
    forEachRow(rig.height, options.threads, [&](int y) {
        auto* grey = greySums.ptr<double>(y);
        auto* bgr = colourSums.ptr<cv::Vec3d>(y);
        for (int x = 0; x < rig.width; ++x) {
            double sum = 0.0;
            Vector3d sumColour = Vector3d::Zero();
            for (int k = 0; k < n * n; ++k) {
                const int stratumColumn = k % n; // the sample's stratum in the n x n grid of the pixel
                const int stratumRow = k / n;
                const double jx = detail::lattice(x, y, 2 * k, jitterSeed);
                const double jy = detail::lattice(x, y, 2 * k + 1, jitterSeed);
                const double u = x - 0.5 + (stratumColumn + jx) / n;
                const double v = y - 0.5 + (stratumRow + jy) / n;
                RayContext ray{x, y, view};
                ray.colour = colour;
                const Radiance r = tracer.radiance(o, tracer.direction(u, v), 0.0, ray);
                sum += r.grey;
                sumColour += r.bgr;
            }
            grey[x] = sum;
            bgr[x] = cv::Vec3d(sumColour.x(), sumColour.y(), sumColour.z());
        }
    });
}

/// Images: the rays of each pixel (traceView), then gains, gradient, vignetting, noise (drawn in pixel order, one
/// thread), JPEG.
void renderImages(const Tracer& tracer, const Scene& scene, const RenderOptions& options, RenderResult& out)
{
    const Rig& rig = scene.rig;
    const Lighting& light = scene.lighting;
    const int n = options.samplesPerAxis;
    const double cornerSq = rig.cx() * rig.cx() + rig.cy() * rig.cy(); // [px^2]
    std::mt19937_64 rng(scene.seed);
    std::normal_distribution<double> noise(0.0, 1.0);
    // Colour noise of its own (the grey image's draws stay as they were): per-channel Gaussian noise less its
    // luminance, so that the colour image's luminance noise is the grey image's.
    constexpr std::uint64_t kChromaNoiseSeed = 0x9e3779b97f4a7c15ULL;
    // (A distribution of its own too: std::normal_distribution keeps the second value of each pair it draws.)
    std::mt19937_64 chromaRng(scene.seed ^ kChromaNoiseSeed);
    std::normal_distribution<double> chromaNoiseDist(0.0, 1.0);
    out.leftColour.create(rig.height, rig.width, CV_8UC3);
    if (options.rightColour) {
        out.rightColour.create(rig.height, rig.width, CV_8UC3);
    }
    cv::Mat greySums;
    cv::Mat colourSums;
    for (int view = 0; view < 2; ++view) {
        cv::Mat& img = view == 0 ? out.left : out.right;
        img.create(rig.height, rig.width, CV_8U);
        const double cameraGain = light.gain * (view == 0 ? 1.0 : light.rightGain);
        const double offset = light.offsetGrey + (view == 0 ? 0.0 : light.rightOffsetGrey); // [grey levels]
        const double vignette = view == 0 ? light.vignetteLeft : light.vignetteRight;
        // The right camera's colour draws its chroma noise after the left's: the left and grey images do not change.
        const bool colour = view == 0 || options.rightColour;
        cv::Mat& colourImg = view == 0 ? out.leftColour : out.rightColour;
        traceView(tracer, scene, options, view, colour, greySums, colourSums);
        for (int y = 0; y < rig.height; ++y) {
            auto* row = img.ptr<std::uint8_t>(y);
            auto* colourRow = colour ? colourImg.ptr<cv::Vec3b>(y) : nullptr;
            const auto* sums = greySums.ptr<double>(y);
            const auto* colourSumRow = colourSums.ptr<cv::Vec3d>(y);
            for (int x = 0; x < rig.width; ++x) {
                const double sum = sums[x];
                const Vector3d sumColour(colourSumRow[x][0], colourSumRow[x][1], colourSumRow[x][2]);
                double gradient = 1.0 + light.gradientX * ((x - rig.cx()) / rig.width) +
                                  light.gradientY * ((y - rig.cy()) / rig.height);
                if (vignette > 0.0) {
                    const double dx = x - rig.cx();
                    const double dy = y - rig.cy();
                    gradient *= 1.0 - vignette * (dx * dx + dy * dy) / cornerSq;
                }
                const double greyNoise = light.noiseSigmaGrey * noise(rng);
                const double grey = 255.0 * cameraGain * gradient * (sum / (n * n)) + offset + greyNoise;
                row[x] = static_cast<std::uint8_t>(std::clamp(std::lround(grey), 0L, 255L));
                if (colour) {
                    Vector3d chromaNoise(chromaNoiseDist(chromaRng), chromaNoiseDist(chromaRng),
                                         chromaNoiseDist(chromaRng));
                    chromaNoise -= Vector3d::Constant(kLuma.dot(chromaNoise));
                    const Vector3d bgr = 255.0 * cameraGain * gradient * (sumColour / (n * n)) +
                                         Vector3d::Constant(offset + greyNoise) + light.noiseSigmaGrey * chromaNoise;
                    for (int c = 0; c < 3; ++c) {
                        colourRow[x][c] = static_cast<std::uint8_t>(std::clamp(std::lround(bgr[c]), 0L, 255L));
                    }
                }
            }
        }
        if (light.jpegQuality > 0) {
            compressJpeg(img, light.jpegQuality);
            if (colour) {
                compressJpeg(colourImg, light.jpegQuality);
            }
        }
    }
}

RenderResult renderUnchecked(const Scene& scene, const Pose& pose, const RenderOptions& options)
{
    const Tracer tracer(scene, pose, options);
    RenderResult out;
    renderTruth(tracer, scene, options, out);
    renderImages(tracer, scene, options, out);
    return out;
}

} // namespace

Result<RenderResult, Error> render(const Scene& scene, const Pose& pose, const RenderOptions& options)
{
    if (auto valid = validate(scene); !valid) {
        return Unexpected(valid.error());
    }
    if (auto valid = validateOptions(options); !valid) {
        return Unexpected(valid.error());
    }
    if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.yawDeg)) {
        return Unexpected(Error{"sim render", "pose must be finite", ""});
    }
    try {
        return renderUnchecked(scene, pose, options);
    } catch (const std::exception& e) { // cv::Mat allocation (cv::Exception, std::bad_alloc)
        return Unexpected(Error{"sim render", std::string("failed: ") + e.what(), "reduce the image size"});
    }
}

Result<RenderResult, Error> renderCourseFrame(const Course& course, std::size_t frame, const RenderOptions& options)
{
    if (frame >= course.poses.size()) {
        return Unexpected(Error{"sim course", "frame " + std::to_string(frame) + " out of range",
                                "use 0.." + std::to_string(course.poses.size()) + " (exclusive)"});
    }
    Scene scene = course.scene;
    scene.seed = course.scene.seed + frame;
    return render(scene, course.poses[frame], options);
}

} // namespace ugv::sim
