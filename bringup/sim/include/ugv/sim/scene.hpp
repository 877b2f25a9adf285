#pragma once

/// @file
/// Scene description of the ray-cast stereo simulator: the stereo rig, the ground texture, lighting,
/// background, obstacles (a tagged struct with factory helpers), a named catalogue of test scenes, and
/// courses (a scene plus a list of vehicle poses) for sequences.
///
/// Frames: the world frame and the vehicle frame are both x forward, y left, z up, with z = 0 the flat
/// ground. The vehicle frame's origin is on the ground below the left camera. Obstacles are placed by
/// horizontal range [m] and bearing [deg] (positive to the left, 0 = x axis) from the world origin, which is
/// the vehicle origin at the pose (0, 0, 0); each factory says which point of the object the range refers to.
///
/// Thread-safety: plain data and pure functions (reentrant). RT-safe: no (host tooling; allocates).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::sim {

/// Ideal, already rectified stereo pair. The right camera is displaced by +baselineM along the camera x axis
/// (to the right). Pixel centres are at integer coordinates; the principal point is the image centre.
struct Rig {
    int width = 640;         ///< [px]
    int height = 480;        ///< [px]
    double focalPx = 546.0;  ///< [px] fx = fy
    double baselineM = 0.30; ///< [m]
    double heightM = 0.59;   ///< [m] left camera centre above the flat ground
    double pitchDeg = 0.0;   ///< [deg] positive = looking down
    double rollDeg = 0.0;    ///< [deg] about the optical axis, positive = right side down

    [[nodiscard]] double cx() const noexcept { return (width - 1) / 2.0; }  ///< [px]
    [[nodiscard]] double cy() const noexcept { return (height - 1) / 2.0; } ///< [px]
    /// Horizontal field of view from the left edge of pixel 0 to the right edge of pixel width-1 [deg].
    [[nodiscard]] double hfovDeg() const noexcept;
};

/// Procedural ground textures (fBm of value noise in world coordinates).
enum class GroundTexture : std::uint8_t { Asphalt, Grass, Gravel, PaintedFloor };

/// A surface colour as a chroma: factors of B, G and R around the grey level, with the luminance
/// 0.114 b + 0.587 g + 0.299 r (ITU-R BT.601, OpenCV's BGR2GRAY) equal to 1, so that the colour image of a surface
/// of grey radiance L is (b, g, r) * L and its luminance is the grey image's L. (1, 1, 1) is neutral grey.
struct Chroma {
    double b = 1.0;
    double g = 1.0;
    double r = 1.0;
};

/// The chroma of a reference colour given as 8-bit B, G, R (any brightness: only the ratios count).
[[nodiscard]] Chroma chromaOf(double b, double g, double r) noexcept;

/// The mean chroma of a ground texture (grass varies around it; see bringup/sim/README.md, "Colour").
[[nodiscard]] Chroma groundChroma(GroundTexture texture) noexcept;

/// Photometric variation. Grey value = 255 * gain * cameraGain * gradient(u, v) * albedo * shading + offset
/// + N(0, noiseSigma), clamped to [0, 255].
struct Lighting {
    double gain = 1.0;            ///< global gain
    double offsetGrey = 0.0;      ///< [grey levels] global offset
    double gradientX = 0.04;      ///< relative brightness change from the left to the right image edge
    double gradientY = 0.03;      ///< relative brightness change from the top to the bottom image edge
    double rightGain = 1.02;      ///< gain of the right camera relative to the left one
    double noiseSigmaGrey = 1.5;  ///< [grey levels] Gaussian sensor noise (seeded by Scene::seed)
    double rightOffsetGrey = 0.0; ///< [grey levels] offset of the right camera added to offsetGrey
    /// Vignetting of each camera: brightness times 1 - k (r / r_corner)^2, r from the principal point, [0, 0.9].
    double vignetteLeft = 0.0;
    double vignetteRight = 0.0;
    int jpegQuality = 0; ///< JPEG compression of both images at this quality (1..100); 0 = none
};

/// Shape of the ground: a height field z_g(x, y) in the world frame, the sum of the terms below; all zero is the
/// flat plane z = 0. The road (carriageway) is
///   z_road(x, y) = -camberSlope |y - crownY| + gradeChange max(0, x - gradeAtX);
/// with a kerb (kerbHeightM > 0), the ground beyond the line y = kerbY (on the side away from y = 0) is a flat
/// pavement at z_road(x, kerbY) + kerbHeightM, joined to the road by a vertical kerb face.
struct GroundShape {
    double camberSlope = 0.0; ///< fall per metre to both sides of the crown line (0.025 = 2.5 %), >= 0
    double crownY = 0.0;      ///< [m] world y of the crown line (it runs along x)
    double gradeChange = 0.0; ///< change of the forward slope at x = gradeAtX (0.04 = +4 %: uphill beyond)
    double gradeAtX = 8.0;    ///< [m] world x where the grade changes
    double kerbY = -2.0;      ///< [m] world y of the kerb face (it runs along x); non-zero
    double kerbHeightM = 0.0; ///< [m] pavement above the road at the kerb; 0 = no kerb
    [[nodiscard]] bool flat() const noexcept { return camberSlope == 0.0 && gradeChange == 0.0 && kerbHeightM == 0.0; }
};

/// Paint and rails on the ground: albedo patterns flush with the surface (not obstacles).
struct Markings {
    std::vector<double> laneLinesY; ///< [m] world y of lane lines running along x
    double lineWidthM = 0.12;       ///< [m]
    double dashM = 3.0;             ///< [m] dash length along x
    double gapM = 6.0;              ///< [m] gap between dashes; 0 = solid lines
    double stopLineX = -1.0;        ///< [m] world x of the near edge of a stop line across the view; < 0 = none
    double stopLineWidthM = 0.3;    ///< [m]
    double paintAlbedo = 0.85;
    bool yellowLines = false;    ///< colour image: lane lines yellow (a centre line) instead of white
    std::vector<double> tracksY; ///< [m] world y of tram track centre lines (two rails each, along x)
    double gaugeM = 1.435;       ///< [m] between the rail centres
    double railWidthM = 0.07;    ///< [m] rail head (polished steel, bright)
    double grooveWidthM = 0.04;  ///< [m] flangeway on the inner side of each rail head (dark)
    double railAlbedo = 0.75;
    double grooveAlbedo = 0.06;
    [[nodiscard]] bool empty() const noexcept { return laneLinesY.empty() && tracksY.empty() && stopLineX < 0.0; }
};

/// A hard shadow on the ground: the ground's albedo times `factor` inside a polygon (world x, y [m], either
/// orientation). Only the ground is shaded (not obstacles, not what a mirror shows).
struct Shadow {
    std::vector<std::pair<double, double>> polygon;
    double factor = 0.3; ///< (0, 1]
};

/// A mirror-like region of the ground (a puddle, or a glossy floor when large): the colour there is
/// (1 - reflectance) * ground + reflectance * what the ray reflected about the ground normal sees. The ground truth
/// is the ground (floor) itself.
struct Reflector {
    double x = 4.0;           ///< [m] world centre
    double y = 0.0;           ///< [m]
    double halfLengthM = 0.8; ///< [m] semi-axis along x
    double halfWidthM = 0.5;  ///< [m] semi-axis along y
    bool round = true;        ///< ellipse, or axis-aligned rectangle
    double reflectance = 0.6; ///< [0, 1]
};

enum class BackgroundType : std::uint8_t { Sky, Walls };

/// What lies beyond the ground: a bright, low-texture sky gradient, or a textured cylindrical wall around
/// the world origin (radius wallDistanceM, height wallHeightM) with sky above it.
struct Background {
    BackgroundType type = BackgroundType::Sky;
    double wallDistanceM = 40.0; ///< [m]
    double wallHeightM = 6.0;    ///< [m]
};

enum class ObstacleType : std::uint8_t {
    Pole,
    TableLegs,
    Box,
    Barrier,
    Curb,
    MeshFence,
    WallWithDoorway,
    Trench,
    Hole,
    Person,
    Overhang,
};

/// One obstacle: a type tag plus the parameters that type uses (see the factories for which and what the
/// placement refers to). The object's centre is at (rangeM + centreOffset) along the bearing, where
/// centreOffset is half the object's extent along its local x axis (radius for round objects).
/// yawDeg rotates the object's local frame (x = depth, y = length/width across) about z, absolute in the
/// world frame (0 = axis-aligned with the vehicle at pose 0).
struct Obstacle {
    ObstacleType type = ObstacleType::Pole;
    double rangeM = 5.0;     ///< [m] horizontal range of the reference point (see factories)
    double bearingDeg = 0.0; ///< [deg] bearing of the reference point, positive to the left
    double yawDeg = 0.0;     ///< [deg] orientation of box-like objects
    double radiusM = 0.06;   ///< [m] pole radius, hole radius, leg/post radius
    double heightM = 1.5;    ///< [m] top height (negative obstacles: unused)
    double lengthM = 1.0;    ///< [m] extent along the local x axis (depth seen from the vehicle)
    double widthM = 1.0;     ///< [m] extent along the local y axis (across)
    double depthM = 0.0;     ///< [m] negative obstacles: depth below the ground
    double elevationM = 0.0; ///< [m] bottom of the object above the ground (overhang slab)
    double gapM = 0.0;       ///< [m] doorway width
    double spacingM = 0.0;   ///< [m] mesh fence wire spacing
    double wireM = 0.0;      ///< [m] mesh fence wire diameter
    bool round = true;       ///< hole: round (radiusM) or square (side widthM)
    double albedo = 0.5;     ///< mean albedo of the procedural texture, (0, 1]
    /// Colour image only: the object's chroma; nullopt = its kind's default (defaultChroma()).
    std::optional<Chroma> chroma;
};

/// The default chroma of an obstacle kind (bringup/sim/README.md, "Colour"); a barrier's dark stripes (its light ones
/// are white), a hole's or trench's soil.
[[nodiscard]] Chroma defaultChroma(ObstacleType type) noexcept;

/// Vertical cylinder; range to its nearest point (centre at range + radius).
[[nodiscard]] Obstacle pole(double rangeM, double bearingDeg, double radiusM = 0.06, double heightM = 1.5);
/// Table: top slab (lengthM x widthM, 0.04 m thick, top at heightM) on 4 legs (radius 0.025 m, inset 0.05 m);
/// range to the near edge of the top (centre at range + length/2).
[[nodiscard]] Obstacle tableLegs(double rangeM, double bearingDeg, double lengthM = 0.8, double widthM = 1.2,
                                 double heightM = 0.75, double yawDeg = 0.0);
/// Box on the ground; range to the near face (centre at range + length/2); yaw 0 = axis-aligned.
[[nodiscard]] Obstacle box(double rangeM, double bearingDeg, double lengthM = 0.5, double widthM = 0.5,
                           double heightM = 0.5, double yawDeg = 0.0);
/// Safety barrier: long low box with diagonal stripes, across the view (widthM across, 0.2 m deep);
/// range to the near face.
[[nodiscard]] Obstacle barrier(double rangeM, double bearingDeg, double widthM = 2.0, double heightM = 0.8,
                               double yawDeg = 0.0);
/// Curb: a step of heightM running across the whole view (40 m long, lengthM deep), perpendicular to the
/// x axis at bearing 0; range to the step face.
[[nodiscard]] Obstacle curb(double rangeM, double heightM = 0.12, double lengthM = 0.3, double bearingDeg = 0.0);
/// Mesh fence: wire grid (wireM diameter, spacingM pitch) in a vertical plane widthM long, heightM high, with
/// posts (radius 0.03 m) at both ends and at most every 2.5 m; range to the wire plane.
[[nodiscard]] Obstacle meshFence(double rangeM, double bearingDeg, double widthM = 4.0, double heightM = 1.5,
                                 double spacingM = 0.075, double wireM = 0.0025, double yawDeg = 0.0);
/// Wall (6 m long, 2 m high, 0.15 m thick) with a doorway of doorWidthM centred on the bearing; range to the
/// near face.
[[nodiscard]] Obstacle wallWithDoorway(double rangeM, double bearingDeg, double doorWidthM = 0.9);
/// Rectangular trench across the view (40 m long), widthM along x, depthM deep; range to its near edge.
[[nodiscard]] Obstacle trench(double rangeM, double widthM, double depthM, double bearingDeg = 0.0);
/// Round (diameterM) or square (side diameterM, axis-aligned) hole; range to its near edge.
[[nodiscard]] Obstacle hole(double rangeM, double bearingDeg, double diameterM, double depthM, bool round = true);
/// Person facing the vehicle (legs, torso, arms, head), heightM tall; range to the front of the torso.
[[nodiscard]] Obstacle person(double rangeM, double bearingDeg, double heightM = 1.7);
/// Horizontal slab (lengthM deep, widthM across, 0.1 m thick) whose underside is elevationM above the
/// ground; range to its near edge. Ground truth: "overhang" when elevationM > clearance, else positive.
[[nodiscard]] Obstacle overhang(double rangeM, double bearingDeg, double elevationM = 1.5, double lengthM = 1.0,
                                double widthM = 2.0);

/// World-frame centre (x, y) of the object's footprint [m]: (rangeM + centreOffset) along the bearing.
[[nodiscard]] std::pair<double, double> obstacleCentre(const Obstacle& obstacle) noexcept;

/// The shadow on flat ground of a pole, box, barrier, curb or table top lit by a sun at the given azimuth (direction
/// towards the sun, counter-clockwise from the world x axis) and elevation: the convex hull of the footprint and
/// of the top outline projected along the sun's rays. The caster need not be in the scene (a tree off the view).
[[nodiscard]] Shadow castShadow(const Obstacle& caster, double sunAzimuthDeg, double sunElevationDeg,
                                double factor = 0.3);

struct Scene {
    Rig rig;
    GroundTexture texture = GroundTexture::Asphalt;
    Lighting lighting;
    Background background;
    std::vector<Obstacle> obstacles; ///< each stands on the ground at its footprint centre
    std::uint64_t seed = 1;          ///< sensor noise and sub-pixel jitter
    /// Colour image only: which hue pattern the grass has (another lawn); the grey images do not depend on it.
    std::uint32_t colourSeed = 0;
    GroundShape ground;
    Markings markings;
    std::vector<Shadow> shadows;
    std::vector<Reflector> reflectors;
};

/// Names accepted by applyCondition(): the real-world conditions of issue 20 (bringup/sim/README.md).
[[nodiscard]] const std::vector<std::string>& conditionNames();

/// Adds a named condition to `scene` (ground shape, photometry, markings, shadows, mirrors); `variant` (>= 0) picks
/// one of a few settings of it (a sweep over the seeds).
/// @return an Error naming the valid conditions for an unknown name.
[[nodiscard]] Result<void, Error> applyCondition(Scene& scene, std::string_view name, int variant = 0);

/// Names accepted by makeScene: "empty" and one per obstacle type.
[[nodiscard]] const std::vector<std::string>& sceneNames();

/// A catalogue scene: default rig, `texture`, one obstacle of the named type at (rangeM, bearingDeg) with its
/// default size ("empty": none). Trench and curb ignore the bearing (they run across the view).
/// @return the scene, or an Error naming the valid scene names.
[[nodiscard]] Result<Scene, Error> makeScene(std::string_view name, double rangeM = 5.0, double bearingDeg = 0.0,
                                             GroundTexture texture = GroundTexture::Asphalt, std::uint64_t seed = 1);

/// Vehicle pose in the world frame.
struct Pose {
    double x = 0.0;      ///< [m]
    double y = 0.0;      ///< [m]
    double yawDeg = 0.0; ///< [deg] counter-clockwise from the world x axis
};

/// A scene in world coordinates plus the vehicle poses of a drive through it.
struct Course {
    Scene scene;
    std::vector<Pose> poses;
};

/// Poses of a straight drive along the world x axis from (0, 0) at speedMps for distanceM, one per frame.
[[nodiscard]] std::vector<Pose> straightDrive(double distanceM, double speedMps, double fps);

/// A named course. "default": 30 m straight drive along x with about a dozen obstacles of mixed types beside
/// and across the path (asphalt, sky).
/// @return the course, or an Error for an unknown name or non-positive speed/fps.
[[nodiscard]] Result<Course, Error> makeCourse(std::string_view name, double speedMps = 1.5, double fps = 10.0);

/// Checks a scene's parameters (rig, lighting, obstacle sizes).
[[nodiscard]] Result<void, Error> validate(const Scene& scene);

} // namespace ugv::sim
