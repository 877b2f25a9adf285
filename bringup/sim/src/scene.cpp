#include "ugv/sim/scene.hpp"

#include "ugv/platform/angles.hpp"
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace ugv::sim {
namespace {

constexpr double kBarrierDepthM = 0.2;      // [m]
constexpr double kAcrossLengthM = 40.0;     // [m] curb and trench length across the view
constexpr double kWallLengthM = 6.0;        // [m]
constexpr double kWallHeightM = 2.0;        // [m]
constexpr double kWallThicknessM = 0.15;    // [m]
constexpr double kPersonRefHeightM = 1.7;   // [m] body proportions are given for this height
constexpr double kPersonTorsoDepthM = 0.25; // [m] at the reference height
constexpr double kOverhangThicknessM = 0.1; // [m]
constexpr double kFencePostRadiusM = 0.03;  // [m]

/// Centre offset along the bearing: half the object's depth (radius for round objects).
double centreOffsetM(const Obstacle& o) noexcept
{
    switch (o.type) {
    case ObstacleType::Pole:
        return o.radiusM;
    case ObstacleType::Hole:
        return o.round ? o.radiusM : o.widthM / 2.0;
    case ObstacleType::MeshFence:
        return 0.0;
    default:
        return o.lengthM / 2.0;
    }
}

Error sceneError(const std::string& what, const std::string& fix)
{
    return Error{"sim scene", what, fix};
}

std::string joined(const std::vector<std::string>& names)
{
    std::string text;
    for (const std::string& n : names) {
        text += text.empty() ? n : ", " + n;
    }
    return text;
}

bool positive(double v) noexcept
{
    return std::isfinite(v) && v > 0.0;
}

/// Places `o` so that its footprint centre is at world (x, y).
Obstacle centredAt(Obstacle o, double x, double y)
{
    o.bearingDeg = std::atan2(y, x) * kRadToDeg;
    o.rangeM = std::hypot(x, y) - centreOffsetM(o);
    return o;
}

using Point = std::pair<double, double>;

/// Convex hull (Andrew's monotone chain), counter-clockwise.
std::vector<Point> convexHull(std::vector<Point> points)
{
    std::sort(points.begin(), points.end());
    points.erase(std::unique(points.begin(), points.end()), points.end());
    if (points.size() < 3) {
        return points;
    }
    const auto cross = [](const Point& o, const Point& a, const Point& b) {
        return (a.first - o.first) * (b.second - o.second) - (a.second - o.second) * (b.first - o.first);
    };
    std::vector<Point> hull(2 * points.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < points.size(); ++i) { // lower hull
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) {
            --k;
        }
        hull[k++] = points[i];
    }
    for (std::size_t i = points.size() - 1, lower = k + 1; i > 0; --i) { // upper hull
        while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i - 1]) <= 0.0) {
            --k;
        }
        hull[k++] = points[i - 1];
    }
    hull.resize(k - 1);
    return hull;
}

/// A value of `values` picked by the variant (cycling).
template <std::size_t N>
double pick(const std::array<double, N>& values, int variant)
{
    return values[static_cast<std::size_t>(std::max(variant, 0)) % N];
}

} // namespace

double Rig::hfovDeg() const noexcept
{
    return 2.0 * std::atan(width / (2.0 * focalPx)) * kRadToDeg;
}

Chroma chromaOf(double b, double g, double r) noexcept
{
    const double luminance = 0.114 * b + 0.587 * g + 0.299 * r;
    if (!(luminance > 0.0)) {
        return {};
    }
    return {b / luminance, g / luminance, r / luminance};
}

Chroma groundChroma(GroundTexture texture) noexcept
{
    // Reference colours (8-bit B, G, R) of the materials in daylight; the README's table lists them.
    switch (texture) {
    case GroundTexture::Grass:
        return chromaOf(45.0, 118.0, 80.0); // between lush (40, 120, 60) and dry (50, 115, 100) grass
    case GroundTexture::Gravel:
        return chromaOf(100.0, 112.0, 125.0); // grey-brown crushed stone
    case GroundTexture::PaintedFloor:
        return chromaOf(95.0, 130.0, 90.0); // green epoxy workshop floor
    case GroundTexture::Asphalt:
        break;
    }
    return chromaOf(92.0, 88.0, 85.0); // dark grey, a trace of blue
}

Chroma defaultChroma(ObstacleType type) noexcept
{
    switch (type) {
    case ObstacleType::Pole:
    case ObstacleType::MeshFence:
        return chromaOf(128.0, 125.0, 122.0); // galvanised steel: grey, close to asphalt (a hard case)
    case ObstacleType::TableLegs:
        return chromaOf(70.0, 110.0, 150.0); // wood
    case ObstacleType::Box:
        return chromaOf(85.0, 130.0, 170.0); // cardboard
    case ObstacleType::Barrier:
        return chromaOf(40.0, 40.0, 200.0); // red stripes (the light stripes are white)
    case ObstacleType::Curb:
    case ObstacleType::Overhang:
        return chromaOf(150.0, 152.0, 155.0); // concrete: near neutral (a hard case on asphalt)
    case ObstacleType::WallWithDoorway:
        return chromaOf(150.0, 180.0, 200.0); // beige plaster
    case ObstacleType::Person:
        return chromaOf(140.0, 80.0, 50.0); // blue jacket and jeans
    case ObstacleType::Trench:
    case ObstacleType::Hole:
        break;
    }
    return chromaOf(50.0, 75.0, 100.0); // brown soil
}

std::pair<double, double> obstacleCentre(const Obstacle& obstacle) noexcept
{
    const double r = obstacle.rangeM + centreOffsetM(obstacle);
    const double b = obstacle.bearingDeg * kDegToRad;
    return {r * std::cos(b), r * std::sin(b)};
}

namespace {

/// An obstacle of `type` at `rangeM` along `bearingDeg` (the factories below give its shape).
Obstacle placed(ObstacleType type, double rangeM, double bearingDeg)
{
    Obstacle o;
    o.type = type;
    o.rangeM = rangeM;
    o.bearingDeg = bearingDeg;
    return o;
}

} // namespace

Obstacle pole(double rangeM, double bearingDeg, double radiusM, double heightM)
{
    Obstacle o = placed(ObstacleType::Pole, rangeM, bearingDeg);
    o.radiusM = radiusM;
    o.heightM = heightM;
    o.albedo = 0.45;
    return o;
}

Obstacle tableLegs(double rangeM, double bearingDeg, double lengthM, double widthM, double heightM, double yawDeg)
{
    Obstacle o = placed(ObstacleType::TableLegs, rangeM, bearingDeg);
    o.lengthM = lengthM;
    o.widthM = widthM;
    o.heightM = heightM;
    o.yawDeg = yawDeg;
    o.radiusM = 0.025;
    o.albedo = 0.6;
    return o;
}

Obstacle box(double rangeM, double bearingDeg, double lengthM, double widthM, double heightM, double yawDeg)
{
    Obstacle o = placed(ObstacleType::Box, rangeM, bearingDeg);
    o.lengthM = lengthM;
    o.widthM = widthM;
    o.heightM = heightM;
    o.yawDeg = yawDeg;
    o.albedo = 0.55;
    return o;
}

Obstacle barrier(double rangeM, double bearingDeg, double widthM, double heightM, double yawDeg)
{
    Obstacle o = box(rangeM, bearingDeg, kBarrierDepthM, widthM, heightM, yawDeg);
    o.type = ObstacleType::Barrier;
    return o;
}

Obstacle curb(double rangeM, double heightM, double lengthM, double bearingDeg)
{
    Obstacle o = box(rangeM, bearingDeg, lengthM, kAcrossLengthM, heightM, 0.0);
    o.type = ObstacleType::Curb;
    o.albedo = 0.65;
    return o;
}

Obstacle meshFence(double rangeM, double bearingDeg, double widthM, double heightM, double spacingM, double wireM,
                   double yawDeg)
{
    Obstacle o = placed(ObstacleType::MeshFence, rangeM, bearingDeg);
    o.widthM = widthM;
    o.heightM = heightM;
    o.spacingM = spacingM;
    o.wireM = wireM;
    o.yawDeg = yawDeg;
    o.radiusM = kFencePostRadiusM;
    o.albedo = 0.8;
    return o;
}

Obstacle wallWithDoorway(double rangeM, double bearingDeg, double doorWidthM)
{
    Obstacle o = placed(ObstacleType::WallWithDoorway, rangeM, bearingDeg);
    o.lengthM = kWallThicknessM;
    o.widthM = kWallLengthM;
    o.heightM = kWallHeightM;
    o.gapM = doorWidthM;
    // Facing the vehicle: the wall runs perpendicular to the bearing.
    o.yawDeg = bearingDeg;
    o.albedo = 0.6;
    return o;
}

Obstacle trench(double rangeM, double widthM, double depthM, double bearingDeg)
{
    Obstacle o = placed(ObstacleType::Trench, rangeM, bearingDeg);
    o.lengthM = widthM;
    o.widthM = kAcrossLengthM;
    o.depthM = depthM;
    o.albedo = 0.4;
    return o;
}

Obstacle hole(double rangeM, double bearingDeg, double diameterM, double depthM, bool round)
{
    Obstacle o = placed(ObstacleType::Hole, rangeM, bearingDeg);
    o.radiusM = diameterM / 2.0;
    o.lengthM = diameterM;
    o.widthM = diameterM;
    o.depthM = depthM;
    o.round = round;
    o.albedo = 0.4;
    return o;
}

Obstacle person(double rangeM, double bearingDeg, double heightM)
{
    Obstacle o = placed(ObstacleType::Person, rangeM, bearingDeg);
    o.heightM = heightM;
    o.lengthM = kPersonTorsoDepthM * heightM / kPersonRefHeightM;
    o.yawDeg = bearingDeg;
    o.albedo = 0.5;
    return o;
}

Obstacle overhang(double rangeM, double bearingDeg, double elevationM, double lengthM, double widthM)
{
    Obstacle o = placed(ObstacleType::Overhang, rangeM, bearingDeg);
    o.elevationM = elevationM;
    o.heightM = elevationM + kOverhangThicknessM;
    o.lengthM = lengthM;
    o.widthM = widthM;
    o.yawDeg = bearingDeg;
    o.albedo = 0.55;
    return o;
}

const std::vector<std::string>& sceneNames()
{
    static const std::vector<std::string> kNames = {"empty",   "pole",        "table",  "box",          "box_yawed",
                                                    "barrier", "curb",        "fence",  "wall_doorway", "trench",
                                                    "hole",    "hole_square", "person", "overhang"};
    return kNames;
}

Result<Scene, Error> makeScene(std::string_view name, double rangeM, double bearingDeg, GroundTexture texture,
                               std::uint64_t seed)
{
    Scene scene;
    scene.texture = texture;
    scene.seed = seed;
    if (name == "empty") {
        return scene;
    }
    if (name == "pole") {
        scene.obstacles.push_back(pole(rangeM, bearingDeg));
    } else if (name == "table") {
        scene.obstacles.push_back(tableLegs(rangeM, bearingDeg));
    } else if (name == "box") {
        scene.obstacles.push_back(box(rangeM, bearingDeg));
    } else if (name == "box_yawed") {
        scene.obstacles.push_back(box(rangeM, bearingDeg, 0.5, 0.8, 0.5, 30.0));
    } else if (name == "barrier") {
        scene.obstacles.push_back(barrier(rangeM, bearingDeg));
    } else if (name == "curb") {
        scene.obstacles.push_back(curb(rangeM));
    } else if (name == "fence") {
        scene.obstacles.push_back(meshFence(rangeM, bearingDeg));
    } else if (name == "wall_doorway") {
        scene.obstacles.push_back(wallWithDoorway(rangeM, bearingDeg));
    } else if (name == "trench") {
        scene.obstacles.push_back(trench(rangeM, 1.0, 0.5));
    } else if (name == "hole") {
        scene.obstacles.push_back(hole(rangeM, bearingDeg, 1.0, 0.5, true));
    } else if (name == "hole_square") {
        scene.obstacles.push_back(hole(rangeM, bearingDeg, 1.0, 0.5, false));
    } else if (name == "person") {
        scene.obstacles.push_back(person(rangeM, bearingDeg));
    } else if (name == "overhang") {
        scene.obstacles.push_back(overhang(rangeM, bearingDeg));
    } else {
        return Unexpected(
            sceneError("unknown scene '" + std::string(name) + "'", "use one of: " + joined(sceneNames())));
    }
    return scene;
}

Shadow castShadow(const Obstacle& caster, double sunAzimuthDeg, double sunElevationDeg, double factor)
{
    constexpr int kRoundCorners = 16;
    Shadow shadow;
    shadow.factor = factor;
    if (caster.type == ObstacleType::Hole || caster.type == ObstacleType::Trench || !(sunElevationDeg > 0.0)) {
        return shadow;
    }
    const auto [cx, cy] = obstacleCentre(caster);
    const double c = std::cos(caster.yawDeg * kDegToRad);
    const double s = std::sin(caster.yawDeg * kDegToRad);
    std::vector<Point> outline; // footprint outline in the world frame
    if (caster.type == ObstacleType::Pole) {
        for (int k = 0; k < kRoundCorners; ++k) {
            const double a = 2.0 * std::numbers::pi * k / kRoundCorners;
            outline.emplace_back(cx + caster.radiusM * std::cos(a), cy + caster.radiusM * std::sin(a));
        }
    } else {
        const double hx = caster.type == ObstacleType::MeshFence ? caster.radiusM : caster.lengthM / 2.0;
        const double hy = caster.widthM / 2.0;
        for (const auto& [lx, ly] : std::array<Point, 4>{{{-hx, -hy}, {hx, -hy}, {hx, hy}, {-hx, hy}}}) {
            outline.emplace_back(cx + c * lx - s * ly, cy + s * lx + c * ly);
        }
    }
    const bool floating = caster.type == ObstacleType::Overhang || caster.type == ObstacleType::TableLegs;
    const double bottom = caster.type == ObstacleType::TableLegs ? caster.heightM - 0.04 : caster.elevationM;
    const double reach = 1.0 / std::tan(sunElevationDeg * kDegToRad); // [m] of shadow per metre of height
    const double ax = -std::cos(sunAzimuthDeg * kDegToRad) * reach;
    const double ay = -std::sin(sunAzimuthDeg * kDegToRad) * reach;
    std::vector<Point> points;
    for (const auto& [x, y] : outline) {
        points.emplace_back(x + ax * caster.heightM, y + ay * caster.heightM);
        points.emplace_back(floating ? Point{x + ax * bottom, y + ay * bottom} : Point{x, y});
    }
    shadow.polygon = convexHull(std::move(points));
    return shadow;
}

const std::vector<std::string>& conditionNames()
{
    static const std::vector<std::string> kNames = {"camber",     "grade_up", "grade_down", "kerb",  "exposure",
                                                    "vignetting", "noise",    "jpeg",       "paint", "rails",
                                                    "shadow",     "glossy",   "puddle"};
    return kNames;
}

namespace {

/// Ground shapes and photometry; false for a name that is neither.
bool applyShapeOrPhotometry(Scene& scene, std::string_view name, int v)
{
    GroundShape& g = scene.ground;
    Lighting& l = scene.lighting;
    if (name == "camber") { // the vehicle in a lane beside the crown, or on it
        g.camberSlope = pick(std::array{0.02, 0.025, 0.03}, v);
        g.crownY = pick(std::array{1.75, 0.0, -1.75}, v);
    } else if (name == "grade_up" || name == "grade_down") {
        g.gradeChange = (name == "grade_up" ? 1.0 : -1.0) * pick(std::array{0.04, 0.03, 0.05}, v);
        g.gradeAtX = pick(std::array{6.0, 4.0, 9.0}, v);
    } else if (name == "kerb") {
        g.kerbY = pick(std::array{-2.0, 1.5, -2.5}, v);
        g.kerbHeightM = pick(std::array{0.12, 0.13, 0.15}, v); // over the 0.10 m of an obstacle
    } else if (name == "exposure") {
        l.rightGain = pick(std::array{0.85, 1.15, 0.9, 1.1}, v);
        l.rightOffsetGrey = pick(std::array{6.0, -6.0, -3.0, 3.0}, v);
    } else if (name == "vignetting") {
        l.vignetteLeft = pick(std::array{0.2, 0.45, 0.0}, v);
        l.vignetteRight = pick(std::array{0.45, 0.2, 0.35}, v);
    } else if (name == "noise") {
        l.noiseSigmaGrey = pick(std::array{4.0, 6.0, 8.0}, v);
    } else if (name == "jpeg") {
        l.jpegQuality = static_cast<int>(pick(std::array{60.0, 80.0, 40.0}, v));
    } else {
        return false;
    }
    return true;
}

/// Markings, shadows and mirrors; false for a name that is none of them.
bool applyAppearance(Scene& scene, std::string_view name, int v)
{
    Markings& m = scene.markings;
    if (name == "paint") { // the vehicle between two lane lines, a stop line ahead
        m.laneLinesY = {1.75, -1.75, 5.25};
        m.gapM = pick(std::array{6.0, 0.0, 3.0}, v);
        m.stopLineX = pick(std::array{6.0, 4.0, 9.0}, v);
    } else if (name == "rails") {
        m.tracksY = {pick(std::array{0.0, 0.6, -0.9}, v)};
    } else if (name == "shadow") { // a building's shadow edge across the path and tree trunks beside it
        const double edge = pick(std::array{5.0, 7.0, 3.5}, v);
        Shadow building;
        building.polygon = {{edge, -30.0}, {edge + 2.0, 30.0}, {60.0, 30.0}, {60.0, -30.0}};
        scene.shadows.push_back(building);
        for (const auto& [x, y] : std::array<Point, 2>{{{3.0, -6.0}, {6.0, 7.0}}}) {
            scene.shadows.push_back(castShadow(centredAt(pole(0.0, 0.0, 0.15, 8.0), x, y), y > 0.0 ? 100.0 : -100.0,
                                               pick(std::array{25.0, 35.0, 20.0}, v)));
        }
    } else if (name == "glossy") { // a polished hall floor
        scene.texture = GroundTexture::PaintedFloor;
        scene.background.type = BackgroundType::Walls;
        Reflector floor;
        floor.round = false;
        floor.halfLengthM = floor.halfWidthM = 1000.0;
        floor.reflectance = pick(std::array{0.5, 0.65, 0.8}, v);
        scene.reflectors.push_back(floor);
    } else if (name == "puddle") {
        Reflector near;
        near.x = pick(std::array{3.0, 4.0, 2.5}, v);
        near.y = pick(std::array{0.3, -0.5, 0.0}, v);
        near.reflectance = pick(std::array{0.7, 0.6, 0.8}, v);
        Reflector far = near;
        far.x += 4.0;
        far.y = -near.y;
        far.halfLengthM = 1.5;
        far.halfWidthM = 0.8;
        scene.reflectors.push_back(near);
        scene.reflectors.push_back(far);
    } else {
        return false;
    }
    return true;
}

} // namespace

Result<void, Error> applyCondition(Scene& scene, std::string_view name, int variant)
{
    if (applyShapeOrPhotometry(scene, name, variant) || applyAppearance(scene, name, variant)) {
        return {};
    }
    return Unexpected(
        sceneError("unknown condition '" + std::string(name) + "'", "use one of: " + joined(conditionNames())));
}

std::vector<Pose> straightDrive(double distanceM, double speedMps, double fps)
{
    std::vector<Pose> poses;
    if (!positive(speedMps) || !positive(fps) || !(distanceM >= 0.0)) {
        return poses;
    }
    const double step = speedMps / fps; // [m] per frame
    const auto frames = static_cast<int>(std::floor(distanceM / step + 1e-9)) + 1;
    poses.reserve(static_cast<std::size_t>(frames));
    for (int k = 0; k < frames; ++k) {
        poses.push_back(Pose{step * k, 0.0, 0.0});
    }
    return poses;
}

Result<Course, Error> makeCourse(std::string_view name, double speedMps, double fps)
{
    if (name != "default") {
        return Unexpected(sceneError("unknown course '" + std::string(name) + "'", "use: default"));
    }
    if (!positive(speedMps) || !positive(fps)) {
        return Unexpected(sceneError("speed and fps must be > 0", "e.g. speed 1.5 m/s at 10 fps"));
    }
    constexpr double kDriveM = 30.0; // [m]
    Course course;
    course.scene.texture = GroundTexture::Asphalt;
    std::vector<Obstacle>& obs = course.scene.obstacles;
    obs.push_back(centredAt(pole(0.0, 0.0, 0.08, 2.0), 6.0, 1.3));
    obs.push_back(centredAt(box(0.0, 0.0, 0.6, 0.6, 0.5, 30.0), 9.0, -1.1));
    obs.push_back(centredAt(person(0.0, 0.0), 12.0, 0.9));
    obs.push_back(centredAt(hole(0.0, 0.0, 0.8, 0.4, true), 14.5, -0.4));
    obs.push_back(centredAt(tableLegs(0.0, 0.0), 17.0, 1.6));
    obs.push_back(centredAt(barrier(0.0, 0.0, 2.0, 0.8, 0.0), 20.0, -1.8));
    obs.push_back(centredAt(meshFence(0.0, 0.0, 3.0, 1.5, 0.075, 0.0025, 0.0), 23.0, 2.5));
    obs.push_back(centredAt(overhang(0.0, 0.0, 1.6, 1.0, 2.5), 26.0, 0.0));
    obs.push_back(centredAt(pole(0.0, 0.0, 0.06, 1.5), 28.0, -0.9));
    obs.push_back(centredAt(trench(0.0, 1.0, 0.5), 36.5, 0.0));
    obs.push_back(centredAt(wallWithDoorway(0.0, 0.0, 0.9), 42.0, 0.0));
    course.poses = straightDrive(kDriveM, speedMps, fps);
    return course;
}

namespace {

bool finite(double v) noexcept
{
    return std::isfinite(v);
}

bool unit(double v) noexcept
{
    return std::isfinite(v) && v >= 0.0 && v <= 1.0;
}

/// The conditions of issue 20: ground shape, per-camera photometry, markings, shadows, mirrors.
Result<void, Error> validateConditions(const Scene& scene)
{
    constexpr double kMaxSlope = 0.3;
    constexpr double kMaxVignette = 0.9;
    constexpr int kMaxJpegQuality = 100;
    const Lighting& l = scene.lighting;
    if (!finite(l.rightOffsetGrey) || !(l.vignetteLeft >= 0.0 && l.vignetteLeft <= kMaxVignette) ||
        !(l.vignetteRight >= 0.0 && l.vignetteRight <= kMaxVignette) || l.jpegQuality < 0 ||
        l.jpegQuality > kMaxJpegQuality) {
        return Unexpected(
            sceneError("lighting: vignetting must be in [0, 0.9], JPEG quality 0..100, offsets finite", ""));
    }
    const GroundShape& g = scene.ground;
    if (!(g.camberSlope >= 0.0 && g.camberSlope <= kMaxSlope) || !(std::abs(g.gradeChange) <= kMaxSlope) ||
        !finite(g.crownY) || !finite(g.gradeAtX) || !(g.kerbHeightM >= 0.0 && g.kerbHeightM <= 1.0) ||
        !finite(g.kerbY) || (g.kerbHeightM > 0.0 && g.kerbY == 0.0)) {
        return Unexpected(sceneError("ground shape: camber in [0, 0.3], grade change in [-0.3, 0.3], kerb height in "
                                     "[0, 1] m with a non-zero kerb y, all finite",
                                     "e.g. camber 0.025, grade 0.04 at 8 m, kerb 0.12 m at y -2 m"));
    }
    const Markings& m = scene.markings;
    bool ok = positive(m.lineWidthM) && positive(m.dashM) && m.gapM >= 0.0 && finite(m.gapM) && finite(m.stopLineX) &&
              positive(m.stopLineWidthM) && positive(m.gaugeM) && positive(m.railWidthM) && m.grooveWidthM >= 0.0 &&
              m.railWidthM + m.grooveWidthM < m.gaugeM && unit(m.paintAlbedo) && unit(m.railAlbedo) &&
              unit(m.grooveAlbedo);
    for (const auto& list : {m.laneLinesY, m.tracksY}) {
        ok = ok && std::all_of(list.begin(), list.end(), finite);
    }
    for (const Shadow& shadow : scene.shadows) {
        ok = ok && shadow.polygon.size() >= 3 && positive(shadow.factor) && shadow.factor <= 1.0 &&
             std::all_of(shadow.polygon.begin(), shadow.polygon.end(),
                         [](const Point& p) { return finite(p.first) && finite(p.second); });
    }
    for (const Reflector& r : scene.reflectors) {
        ok = ok && finite(r.x) && finite(r.y) && positive(r.halfLengthM) && positive(r.halfWidthM) &&
             unit(r.reflectance);
    }
    if (!ok) {
        return Unexpected(sceneError("markings, shadows or reflectors: non-positive size, albedo or reflectance "
                                     "outside [0, 1], shadow with fewer than 3 corners, or a non-finite value",
                                     "use the defaults of Markings, Shadow and Reflector as a reference"));
    }
    return {};
}

} // namespace

Result<void, Error> validate(const Scene& scene)
{
    if (auto conditions = validateConditions(scene); !conditions) {
        return conditions;
    }
    const Rig& rig = scene.rig;
    if (rig.width < 2 || rig.height < 2 || rig.width > 8192 || rig.height > 8192) {
        return Unexpected(
            sceneError("image size " + std::to_string(rig.width) + "x" + std::to_string(rig.height) + " out of range",
                       "use 2..8192 px per side"));
    }
    if (!positive(rig.focalPx) || !positive(rig.baselineM) || !positive(rig.heightM)) {
        return Unexpected(sceneError("focal, baseline and camera height must be > 0", "e.g. 546 px, 0.30 m, 0.59 m"));
    }
    if (!(std::abs(rig.pitchDeg) < 80.0) || !(std::abs(rig.rollDeg) < 80.0)) {
        return Unexpected(sceneError("pitch/roll must be within +-80 deg", ""));
    }
    const Lighting& l = scene.lighting;
    if (!positive(l.gain) || !positive(l.rightGain) || !(l.noiseSigmaGrey >= 0.0) || !std::isfinite(l.offsetGrey) ||
        !std::isfinite(l.gradientX) || !std::isfinite(l.gradientY)) {
        return Unexpected(sceneError("lighting: gains must be > 0, noise >= 0, all finite", ""));
    }
    if (scene.background.type == BackgroundType::Walls &&
        (!positive(scene.background.wallDistanceM) || !positive(scene.background.wallHeightM))) {
        return Unexpected(sceneError("background wall distance and height must be > 0", ""));
    }
    for (std::size_t i = 0; i < scene.obstacles.size(); ++i) {
        const Obstacle& o = scene.obstacles[i];
        const std::string where = "obstacle " + std::to_string(i) + ": ";
        if (!(o.rangeM >= 0.0) || !std::isfinite(o.rangeM) || !std::isfinite(o.bearingDeg) ||
            !std::isfinite(o.yawDeg)) {
            return Unexpected(sceneError(where + "range must be >= 0 and angles finite", ""));
        }
        if (!positive(o.albedo) || o.albedo > 1.0) {
            return Unexpected(sceneError(where + "albedo must be in (0, 1]", ""));
        }
        bool ok = true;
        switch (o.type) {
        case ObstacleType::Pole:
            ok = positive(o.radiusM) && positive(o.heightM);
            break;
        case ObstacleType::Hole:
            ok = positive(o.depthM) && (o.round ? positive(o.radiusM) : positive(o.widthM));
            break;
        case ObstacleType::Trench:
            ok = positive(o.depthM) && positive(o.lengthM) && positive(o.widthM);
            break;
        case ObstacleType::MeshFence:
            ok = positive(o.widthM) && positive(o.heightM) && positive(o.spacingM) && positive(o.wireM) &&
                 o.wireM < o.spacingM && positive(o.radiusM);
            break;
        case ObstacleType::WallWithDoorway:
            ok = positive(o.lengthM) && positive(o.widthM) && positive(o.heightM) && positive(o.gapM) &&
                 o.gapM < o.widthM;
            break;
        case ObstacleType::Overhang:
            ok = positive(o.lengthM) && positive(o.widthM) && positive(o.elevationM) && o.heightM > o.elevationM;
            break;
        case ObstacleType::TableLegs:
            ok = positive(o.lengthM) && positive(o.widthM) && o.heightM > 0.1 && positive(o.radiusM) &&
                 o.lengthM > 4.0 * o.radiusM && o.widthM > 4.0 * o.radiusM;
            break;
        case ObstacleType::Person:
            ok = positive(o.heightM) && positive(o.lengthM);
            break;
        case ObstacleType::Box:
        case ObstacleType::Barrier:
        case ObstacleType::Curb:
            ok = positive(o.lengthM) && positive(o.widthM) && positive(o.heightM);
            break;
        }
        if (!ok) {
            return Unexpected(sceneError(where + "non-positive or inconsistent size parameter",
                                         "use the factory defaults as a reference"));
        }
    }
    return {};
}

} // namespace ugv::sim
