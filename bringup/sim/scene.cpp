#include "sim/scene.hpp"

#include <cmath>
#include <numbers>

namespace ugv::sim {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr double kTableTopM = 0.75;         // [m]
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

} // namespace

double Rig::hfovDeg() const noexcept
{
    return 2.0 * std::atan(width / (2.0 * focalPx)) * kRadToDeg;
}

std::pair<double, double> obstacleCentre(const Obstacle& obstacle) noexcept
{
    const double r = obstacle.rangeM + centreOffsetM(obstacle);
    const double b = obstacle.bearingDeg * kDegToRad;
    return {r * std::cos(b), r * std::sin(b)};
}

Obstacle pole(double rangeM, double bearingDeg, double radiusM, double heightM)
{
    Obstacle o;
    o.type = ObstacleType::Pole;
    o.rangeM = rangeM;
    o.bearingDeg = bearingDeg;
    o.radiusM = radiusM;
    o.heightM = heightM;
    o.albedo = 0.45;
    return o;
}

Obstacle tableLegs(double rangeM, double bearingDeg, double lengthM, double widthM, double heightM, double yawDeg)
{
    Obstacle o;
    o.type = ObstacleType::TableLegs;
    o.rangeM = rangeM;
    o.bearingDeg = bearingDeg;
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
    Obstacle o;
    o.type = ObstacleType::Box;
    o.rangeM = rangeM;
    o.bearingDeg = bearingDeg;
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
    Obstacle o;
    o.type = ObstacleType::MeshFence;
    o.rangeM = rangeM;
    o.bearingDeg = bearingDeg;
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
    Obstacle o;
    o.type = ObstacleType::WallWithDoorway;
    o.rangeM = rangeM;
    o.bearingDeg = bearingDeg;
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
    Obstacle o;
    o.type = ObstacleType::Trench;
    o.rangeM = rangeM;
    o.bearingDeg = bearingDeg;
    o.lengthM = widthM;
    o.widthM = kAcrossLengthM;
    o.depthM = depthM;
    o.albedo = 0.4;
    return o;
}

Obstacle hole(double rangeM, double bearingDeg, double diameterM, double depthM, bool round)
{
    Obstacle o;
    o.type = ObstacleType::Hole;
    o.rangeM = rangeM;
    o.bearingDeg = bearingDeg;
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
    Obstacle o;
    o.type = ObstacleType::Person;
    o.rangeM = rangeM;
    o.bearingDeg = bearingDeg;
    o.heightM = heightM;
    o.lengthM = kPersonTorsoDepthM * heightM / kPersonRefHeightM;
    o.yawDeg = bearingDeg;
    o.albedo = 0.5;
    return o;
}

Obstacle overhang(double rangeM, double bearingDeg, double elevationM, double lengthM, double widthM)
{
    Obstacle o;
    o.type = ObstacleType::Overhang;
    o.rangeM = rangeM;
    o.bearingDeg = bearingDeg;
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
        std::string known;
        for (const std::string& n : sceneNames()) {
            known += known.empty() ? n : ", " + n;
        }
        return Unexpected(sceneError("unknown scene '" + std::string(name) + "'", "use one of: " + known));
    }
    return scene;
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

Result<void, Error> validate(const Scene& scene)
{
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
