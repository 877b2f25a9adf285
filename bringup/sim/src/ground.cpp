#include "ugv/sim/ground.hpp"

#include <algorithm>
#include <cmath>

namespace ugv::sim::detail {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTinyDir = 1e-12; // direction components below this count as parallel
constexpr double kSeamM = 1e-9;    // [m] regions overlap by this at their seams (the surface is continuous there)

/// Fraction of [a - w/2, a + w/2] inside [lo, hi].
double intervalCoverage(double a, double w, double lo, double hi) noexcept
{
    if (w <= 1e-12) {
        return a >= lo && a < hi ? 1.0 : 0.0;
    }
    return std::clamp((std::min(a + w / 2.0, hi) - std::max(a - w / 2.0, lo)) / w, 0.0, 1.0);
}

bool insidePolygon(const std::vector<std::pair<double, double>>& polygon, double x, double y) noexcept
{
    bool inside = false;
    for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
        const auto& [xi, yi] = polygon[i];
        const auto& [xj, yj] = polygon[j];
        if ((yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi) {
            inside = !inside;
        }
    }
    return inside;
}

} // namespace

double wireCoverage(double a, double w, double spacing, double wire) noexcept
{
    const auto cumulative = [&](double x) {
        const double shifted = x + wire / 2.0;
        const double cells = std::floor(shifted / spacing);
        return cells * wire + std::min(shifted - cells * spacing, wire);
    };
    if (w <= 1e-12) {
        const double m = a + wire / 2.0 - std::floor((a + wire / 2.0) / spacing) * spacing;
        return m < wire ? 1.0 : 0.0;
    }
    return std::clamp((cumulative(a + w / 2.0) - cumulative(a - w / 2.0)) / w, 0.0, 1.0);
}

GroundModel::GroundModel(const GroundShape& shape) : shape_(shape)
{
    const bool graded = shape.gradeChange != 0.0;
    const bool kerb = shape.kerbHeightM > 0.0;
    std::vector<double> xs = {-kInf};
    if (graded) {
        xs.push_back(shape.gradeAtX);
    }
    xs.push_back(kInf);
    std::vector<double> ys = {-kInf, kInf};
    if (shape.camberSlope != 0.0) {
        ys.push_back(shape.crownY);
    }
    if (kerb) {
        ys.push_back(shape.kerbY);
    }
    std::sort(ys.begin(), ys.end());
    ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
    const auto inner = [](double lo, double hi) { // a point inside (lo, hi)
        return std::isfinite(lo) ? (std::isfinite(hi) ? (lo + hi) / 2.0 : lo + 1.0)
                                 : (std::isfinite(hi) ? hi - 1.0 : 0.0);
    };
    for (std::size_t i = 0; i + 1 < xs.size(); ++i) {
        for (std::size_t k = 0; k + 1 < ys.size(); ++k) {
            Region r{xs[i], xs[i + 1], ys[k], ys[k + 1], {}, GroundPart::Road};
            const bool beyondGrade = graded && inner(r.x0, r.x1) > shape.gradeAtX;
            r.plane.cx = beyondGrade ? shape.gradeChange : 0.0;
            r.plane.c0 = beyondGrade ? -shape.gradeChange * shape.gradeAtX : 0.0;
            if (onPavement(inner(r.y0, r.y1))) {
                r.part = GroundPart::Pavement;
                r.plane.c0 += shape.kerbHeightM - shape.camberSlope * std::abs(shape.kerbY - shape.crownY);
            } else {
                const double side = inner(r.y0, r.y1) >= shape.crownY ? -1.0 : 1.0; // falls away from the crown
                r.plane.cy = side * shape.camberSlope;
                r.plane.c0 -= side * shape.camberSlope * shape.crownY;
            }
            regions_.push_back(r);
        }
    }
}

bool GroundModel::onPavement(double y) const noexcept
{
    return shape_.kerbHeightM > 0.0 && (shape_.kerbY < 0.0 ? y < shape_.kerbY : y > shape_.kerbY);
}

double GroundModel::roadHeight(double x, double y) const noexcept
{
    return -shape_.camberSlope * std::abs(y - shape_.crownY) + shape_.gradeChange * std::max(0.0, x - shape_.gradeAtX);
}

double GroundModel::height(double x, double y) const noexcept
{
    return onPavement(y) ? roadHeight(x, shape_.kerbY) + shape_.kerbHeightM : roadHeight(x, y);
}

double GroundModel::maxSlope() const noexcept
{
    return shape_.camberSlope + std::abs(shape_.gradeChange);
}

GroundHit GroundModel::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMin) const noexcept
{
    GroundHit best;
    for (const Region& r : regions_) {
        const GroundPlane& p = r.plane;
        const double denom = d.z() - p.cx * d.x() - p.cy * d.y();
        if (std::abs(denom) < kTinyDir) {
            continue;
        }
        const double t = (p.at(o.x(), o.y()) - o.z()) / denom;
        if (!(t > tMin && t < best.t)) {
            continue;
        }
        const double x = o.x() + t * d.x();
        const double y = o.y() + t * d.y();
        if (x >= r.x0 - kSeamM && x <= r.x1 + kSeamM && y >= r.y0 - kSeamM && y <= r.y1 + kSeamM) {
            best.t = t;
            best.part = r.part;
            best.plane = p;
            best.n = Eigen::Vector3d(-p.cx, -p.cy, 1.0).normalized();
        }
    }
    // The kerb face y = kerbY, seen from the road (the ray heads towards the pavement side).
    if (shape_.kerbHeightM > 0.0 && d.y() * shape_.kerbY > kTinyDir) {
        const double t = (shape_.kerbY - o.y()) / d.y();
        const double z = o.z() + t * d.z();
        const double road = roadHeight(o.x() + t * d.x(), shape_.kerbY);
        if (t > tMin && t < best.t && z >= road && z <= road + shape_.kerbHeightM) {
            best.t = t;
            best.part = GroundPart::KerbFace;
            best.n = Eigen::Vector3d(0.0, shape_.kerbY < 0.0 ? 1.0 : -1.0, 0.0);
        }
    }
    return best;
}

GroundLook::GroundLook(const Scene& scene) : shadows_(scene.shadows), reflectors_(scene.reflectors)
{
    const auto vec = [](const Chroma& c) { return Eigen::Vector3d(c.b, c.g, c.r); };
    const Eigen::Vector3d white(1.0, 1.0, 1.0);
    const Eigen::Vector3d yellow = vec(chromaOf(40.0, 190.0, 230.0)); // road-marking yellow
    const Eigen::Vector3d steel = vec(chromaOf(200.0, 195.0, 190.0)); // polished rail head, faintly blue
    const Markings& m = scene.markings;
    const double period = m.gapM > 0.0 ? m.dashM + m.gapM : 0.0;
    for (const double y : m.laneLinesY) {
        stripes_.push_back({y, m.lineWidthM, m.paintAlbedo, period, m.dashM, true, m.yellowLines ? yellow : white});
    }
    if (m.stopLineX >= 0.0) {
        stripes_.push_back(
            {m.stopLineX + m.stopLineWidthM / 2.0, m.stopLineWidthM, m.paintAlbedo, 0.0, 0.0, false, white});
    }
    for (const double y : m.tracksY) {
        for (const double side : {-1.0, 1.0}) {
            const double rail = y + side * m.gaugeM / 2.0;
            const double groove = rail - side * (m.railWidthM + m.grooveWidthM) / 2.0; // inside the track
            stripes_.push_back({rail, m.railWidthM, m.railAlbedo, 0.0, 0.0, true, steel});
            if (m.grooveWidthM > 0.0) {
                stripes_.push_back({groove, m.grooveWidthM, m.grooveAlbedo, 0.0, 0.0, true, white});
            }
        }
    }
}

double GroundLook::coverage(const Stripe& s, double x, double y, double footprint) noexcept
{
    const double across = s.alongX ? y : x;
    double covered = intervalCoverage(across, footprint, s.centre - s.width / 2.0, s.centre + s.width / 2.0);
    if (covered > 0.0 && s.period > 0.0) {
        covered *= wireCoverage(x, footprint, s.period, s.dash);
    }
    return covered;
}

double GroundLook::albedo(double albedo, double x, double y, double footprint) const noexcept
{
    for (const Stripe& s : stripes_) {
        albedo += coverage(s, x, y, footprint) * (s.albedo - albedo);
    }
    for (const Shadow& shadow : shadows_) {
        if (insidePolygon(shadow.polygon, x, y)) {
            albedo *= shadow.factor;
        }
    }
    return albedo;
}

Eigen::Vector3d GroundLook::colour(Eigen::Vector3d colour, double x, double y, double footprint) const noexcept
{
    for (const Stripe& s : stripes_) {
        colour += coverage(s, x, y, footprint) * (s.albedo * s.chroma - colour);
    }
    for (const Shadow& shadow : shadows_) {
        if (insidePolygon(shadow.polygon, x, y)) {
            colour *= shadow.factor; // a shadow darkens; its chroma stays the surface's
        }
    }
    return colour;
}

double GroundLook::reflectance(double x, double y) const noexcept
{
    double best = 0.0;
    for (const Reflector& r : reflectors_) {
        const double u = (x - r.x) / r.halfLengthM;
        const double v = (y - r.y) / r.halfWidthM;
        const bool inside = r.round ? u * u + v * v <= 1.0 : std::abs(u) <= 1.0 && std::abs(v) <= 1.0;
        best = inside ? std::max(best, r.reflectance) : best;
    }
    return best;
}

} // namespace ugv::sim::detail
