// A second DDS implementation on the service's bus (issue 23): a Cyclone DDS participant with its own types
// (ros2_ugvsense.idl, written from the ROS 2 message definitions) that
//  - discovers the service and reads its ROS 2 topics rt/<ns>/obstacle_scan and rt/<ns>/clear_scan
//    (sensor_msgs/LaserScan; the second's range_max is the clear range) and rt/<ns>/negative_obstacles
//    (sensor_msgs/PointCloud2) with a reliable reader (ROS 2's default QoS), or a best-effort one (--best-effort),
//    and checks every field of every sample;
//  - reads ugvsense/sectors to check the scan's ray semantics against the sectors of the same frame (clear -> +inf,
//    unknown -> NaN, obstacle -> its range at the sector's centre bearing, and in the clearing scan +inf at or beyond
//    its range_max; every cloud point on a negative obstacle sector's ray);
//  - writes ugvsense/pose (VehiclePose) at 10 Hz with a marker position and checks that the service uses it
//    (ugvsense/sectors carries it, valid and not stale);
//  - applies Nav2's obstacle layer rules (nav2_costmap_2d ObstacleLayer + ObservationBuffer + laser_geometry, Humble)
//    to each frame on a 5 cm grid in the scan's frame: every published negative obstacle point must be marked, and
//    no cell beyond what a Clear sector guarantees (--clear-range) may be cleared;
//  - with --truth and --drop: places each published drop point in the course (its frame is the sectors'
//    sequence_number modulo the course's frame count: the replay continues the sequence across loops) and requires
//    it on one of the course's drops, and every drop published and marked.
// The Nav2 parameters are given as SOURCE.KEY=VALUE (layer.min_obstacle_height=-5.0, clear.raytrace_max_range=15,
// negatives.max_obstacle_height=0.0, ...: the test script reads them from README.md's Nav2 block); a key not given
// has Nav2's default. Exit 0 when every check passes, 1 on a failed check, 2 on a usage or DDS setup error.
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dds/dds.h"
#include "ros2_ugvsense.h"

enum {
    kMaxRays = 180,      // one ray per sector (ugvsense.idl MAX_SECTORS)
    kRing = 64,          // frames kept for pairing the scan, the cloud and the sectors of one capture
    kMaxSamples = 16,    // taken per dds_take
    kMaxFailures = 12,   // printed; the rest are counted
    kPointStep = 12,     // x, y, z float32
    kMaxNameLength = 64, // ugvsense names
    kFloat32 = sensor_msgs_msg_dds__PointField_Constants_FLOAT32,
};

static const double kCellM = 0.05;             // Nav2's default costmap resolution [m]
static const double kGridMinX = -1.0;          // the grid in the scan's frame [m]
static const double kGridMaxX = 52.0;          // beyond range_max (50 m)
static const double kGridHalfY = 27.0;         // [m]
static const double kNav2InfEpsilon = 0.0001;  // ObstacleLayer::laserScanValidInfCallback: +inf -> range_max - eps
static const double kAngleTolRad = 2e-4;       // float rounding of the angles (float32 increment x 180 rays)
static const double kRangeTolM = 1e-3;         // a cloud point's horizontal range vs. its ray's (float32 cos/sin)
static const double kMaxStampAgeS = 2.0;       // a sample's stamp against this host's clock (same host)
static const double kPoseMarkerEastM = 123.25; // our pose: exact in binary, so interpolation keeps it exact
static const double kPoseMarkerNorthM = -45.5;
static const double kPoseHeadingDeg = 90.0;

// ---- options ---------------------------------------------------------------------------------------------------

/// One observation source of Nav2's obstacle layer; defaults are nav2_costmap_2d's (obstacle_layer.cpp, Humble).
typedef struct {
    double minObstacleHeight; // [m] ObservationBuffer: points outside [min, max] (global frame z) are dropped
    double maxObstacleHeight; // [m]
    double obstacleMaxRange;  // [m] 3-D distance from the sensor origin; marking only below it
    double obstacleMinRange;  // [m]
    double raytraceMaxRange;  // [m] clearing rays are cut to this length
    double raytraceMinRange;  // [m]
    bool infIsValid;          // LaserScan: +inf becomes range_max - epsilon (a ray that clears)
    bool marking;
    bool clearing;
    bool present; // in observation_sources: some key of it is given
    char topic[128];
} Nav2Source;

typedef struct {
    double minObstacleHeight; // [m] the layer's own filter (PR #3211), default 0
    double maxObstacleHeight; // [m] default 2
    Nav2Source scan;          // ugvsense_scan: rt/<ns>/obstacle_scan
    Nav2Source clear;         // ugvsense_clear: rt/<ns>/clear_scan
    Nav2Source negatives;     // ugvsense_negatives: rt/<ns>/negative_obstacles
} Nav2Layer;

/// A negative obstacle of the course, in the course's frame (x forward along the drive, y left) [m].
typedef struct {
    char name[32];
    double x, y, halfX, halfY;
    long points, marked;
} Drop;

enum { kMaxDrops = 8, kMaxCourseFrames = 4096 };
static const double kDropMarginM = 0.5; // stereo range error at the rim, and the rim vs. the drop's edge

typedef struct {
    int domain;
    const char* ns;
    const char* frame;
    const char* vehicle;
    const char* participant; ///< the service's participant name, or NULL
    double durationS;        ///< at most [s]
    double minDurationS;     ///< at least [s] (poses written meanwhile), then until every expectation is met
    int minFrames;
    bool bestEffort;
    bool verbose;
    double clearRangeM;
    double minDepthM;
    Nav2Layer nav2;
    const char* truthPath;
    Drop drops[kMaxDrops];
    int dropCount;
    const char* enclave; ///< an SROS2 enclave folder: DDS Security as rmw_cyclonedds_cpp sets it up, ROS topics only
    bool expectDenied;   ///< pass only when nothing of the service is discovered or received (no valid certificate)
} Options;

/// Whether the run reads ugvsense/sectors and writes ugvsense/pose: not as a ROS 2 node (an enclave), whose
/// permissions allow none of ugvsense/*.
static bool usesOurTopics(const Options* o)
{
    return o->enclave == NULL;
}

static Nav2Source nav2SourceDefaults(bool clearing)
{
    const Nav2Source s = {.minObstacleHeight = 0.0,
                          .maxObstacleHeight = 0.0,
                          .obstacleMaxRange = 2.5,
                          .obstacleMinRange = 0.0,
                          .raytraceMaxRange = 3.0,
                          .raytraceMinRange = 0.0,
                          .infIsValid = false,
                          .marking = true,
                          .clearing = clearing};
    return s;
}

static bool parseBool(const char* v, bool* out)
{
    if (strcmp(v, "true") == 0 || strcmp(v, "True") == 0) {
        *out = true;
        return true;
    }
    if (strcmp(v, "false") == 0 || strcmp(v, "False") == 0) {
        *out = false;
        return true;
    }
    return false;
}

static bool parseDouble(const char* v, double* out)
{
    char* end = NULL;
    errno = 0;
    const double d = strtod(v, &end);
    if (errno != 0 || end == v || *end != '\0' || !isfinite(d)) {
        return false;
    }
    *out = d;
    return true;
}

/// SOURCE.KEY=VALUE with SOURCE layer, scan or negatives. Keys the consumer does not need (plugin, data_type,
/// observation_sources) are accepted and ignored; an unknown key is an error, so that a README change that this
/// consumer does not model is noticed.
static bool setNav2(Nav2Layer* n, const char* arg)
{
    char buf[256];
    if (strlen(arg) >= sizeof buf) {
        return false;
    }
    strcpy(buf, arg);
    char* eq = strchr(buf, '=');
    char* dot = strchr(buf, '.');
    if (eq == NULL || dot == NULL || dot > eq) {
        return false;
    }
    *eq = '\0';
    *dot = '\0';
    const char* src = buf;
    const char* key = dot + 1;
    const char* val = eq + 1;
    if (strcmp(src, "layer") == 0) {
        if (strcmp(key, "min_obstacle_height") == 0) {
            return parseDouble(val, &n->minObstacleHeight);
        }
        if (strcmp(key, "max_obstacle_height") == 0) {
            return parseDouble(val, &n->maxObstacleHeight);
        }
        return strcmp(key, "plugin") == 0 || strcmp(key, "observation_sources") == 0;
    }
    Nav2Source* s = strcmp(src, "scan") == 0        ? &n->scan
                    : strcmp(src, "clear") == 0     ? &n->clear
                    : strcmp(src, "negatives") == 0 ? &n->negatives
                                                    : NULL;
    if (s == NULL) {
        return false;
    }
    s->present = true;
    if (strcmp(key, "min_obstacle_height") == 0) {
        return parseDouble(val, &s->minObstacleHeight);
    }
    if (strcmp(key, "max_obstacle_height") == 0) {
        return parseDouble(val, &s->maxObstacleHeight);
    }
    if (strcmp(key, "obstacle_max_range") == 0) {
        return parseDouble(val, &s->obstacleMaxRange);
    }
    if (strcmp(key, "obstacle_min_range") == 0) {
        return parseDouble(val, &s->obstacleMinRange);
    }
    if (strcmp(key, "raytrace_max_range") == 0) {
        return parseDouble(val, &s->raytraceMaxRange);
    }
    if (strcmp(key, "raytrace_min_range") == 0) {
        return parseDouble(val, &s->raytraceMinRange);
    }
    if (strcmp(key, "inf_is_valid") == 0) {
        return parseBool(val, &s->infIsValid);
    }
    if (strcmp(key, "marking") == 0) {
        return parseBool(val, &s->marking);
    }
    if (strcmp(key, "clearing") == 0) {
        return parseBool(val, &s->clearing);
    }
    if (strcmp(key, "topic") == 0) {
        snprintf(s->topic, sizeof s->topic, "%s", val);
        return true;
    }
    return strcmp(key, "data_type") == 0;
}

static void usage(void)
{
    fprintf(stderr,
            "usage: cyclone_interop --domain N --ns NS --frame FRAME_ID --vehicle ID [--duration MAX_S] "
            "[--min-duration S]\n"
            "         [--frames N] [--participant NAME] [--enclave DIR] [--expect-denied]\n"
            "         [--best-effort] [--verbose] [--clear-range M] [--min-depth M]\n"
            "         [--truth REC.ugvrec.truth.csv --drop NAME:X,Y,HALF_X,HALF_Y ...] [SOURCE.KEY=VALUE ...]\n"
            "  --truth: the replayed course's truth (ego pose per frame); --drop: a negative obstacle of the course\n"
            "  (centre and half extents in the course's frame): every published drop point must lie on one, and each\n"
            "  must be published and marked\n"
            "  --enclave: join a secured bus as a ROS 2 node with this SROS2 enclave (its six files, the plugins as\n"
            "  rmw_cyclonedds_cpp loads them); it then reads and checks the ROS 2 topics only (a ROS 2 node's\n"
            "  permissions allow none of ugvsense/*)\n"
            "  --expect-denied: succeed only if, for the whole --duration, no writer or reader of the service matches\n"
            "  and no sample arrives (a participant without a certificate, or with another CA's, on a secured bus)\n"
            "  SOURCE: layer | scan | clear | negatives; KEY: a Nav2 obstacle layer parameter (min_obstacle_height,\n"
            "  max_obstacle_height, obstacle_max_range, raytrace_max_range, inf_is_valid, marking, clearing, ...)\n");
}

static bool parseOptions(int argc, char** argv, Options* o)
{
    *o = (Options){
        .domain = -1, .durationS = 15.0, .minDurationS = 5.0, .minFrames = 20, .clearRangeM = 5.0, .minDepthM = 0.10};
    o->nav2.minObstacleHeight = 0.0;
    o->nav2.maxObstacleHeight = 2.0;
    o->nav2.scan = nav2SourceDefaults(false);
    o->nav2.clear = nav2SourceDefaults(false);
    o->nav2.negatives = nav2SourceDefaults(false);
    for (int i = 1; i < argc; ++i) {
        const char* a = argv[i];
        const char* v = i + 1 < argc ? argv[i + 1] : NULL;
        double d = 0.0;
        if (strcmp(a, "--best-effort") == 0) {
            o->bestEffort = true;
        } else if (strcmp(a, "--verbose") == 0) {
            o->verbose = true;
        } else if (strcmp(a, "--expect-denied") == 0) {
            o->expectDenied = true;
        } else if (strchr(a, '=') != NULL && a[0] != '-') {
            if (!setNav2(&o->nav2, a)) {
                fprintf(stderr, "cyclone_interop: bad or unmodelled Nav2 parameter '%s'\n", a);
                return false;
            }
        } else if (v == NULL) {
            usage();
            return false;
        } else if (strcmp(a, "--domain") == 0 && parseDouble(v, &d) && d >= 0 && d <= 232) {
            o->domain = (int)d;
            ++i;
        } else if (strcmp(a, "--ns") == 0) {
            o->ns = argv[++i];
        } else if (strcmp(a, "--participant") == 0) {
            o->participant = argv[++i];
        } else if (strcmp(a, "--enclave") == 0) {
            o->enclave = argv[++i];
        } else if (strcmp(a, "--frame") == 0) {
            o->frame = argv[++i];
        } else if (strcmp(a, "--vehicle") == 0 && strlen(v) > 0 && strlen(v) <= kMaxNameLength) {
            o->vehicle = argv[++i];
        } else if (strcmp(a, "--duration") == 0 && parseDouble(v, &o->durationS) && o->durationS > 0) {
            ++i;
        } else if (strcmp(a, "--min-duration") == 0 && parseDouble(v, &o->minDurationS) && o->minDurationS >= 0) {
            ++i;
        } else if (strcmp(a, "--frames") == 0 && parseDouble(v, &d) && d >= 1) {
            o->minFrames = (int)d;
            ++i;
        } else if (strcmp(a, "--clear-range") == 0 && parseDouble(v, &o->clearRangeM) && o->clearRangeM > 0) {
            ++i;
        } else if (strcmp(a, "--min-depth") == 0 && parseDouble(v, &o->minDepthM) && o->minDepthM >= 0) {
            ++i;
        } else if (strcmp(a, "--truth") == 0) {
            o->truthPath = argv[++i];
        } else if (strcmp(a, "--drop") == 0 && o->dropCount < kMaxDrops) {
            Drop* d = &o->drops[o->dropCount++];
            if (sscanf(v, "%31[^:]:%lf,%lf,%lf,%lf", d->name, &d->x, &d->y, &d->halfX, &d->halfY) != 5) {
                usage();
                return false;
            }
            ++i;
        } else {
            usage();
            return false;
        }
    }
    if (o->domain < 0 || o->ns == NULL || o->frame == NULL || o->vehicle == NULL) {
        usage();
        return false;
    }
    return true;
}

// ---- checks ----------------------------------------------------------------------------------------------------

static int failures = 0;

static void fail(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
static void fail(const char* fmt, ...)
{
    if (++failures <= kMaxFailures) {
        va_list ap;
        va_start(ap, fmt);
        fputs("FAIL: ", stdout);
        vprintf(fmt, ap);
        fputc('\n', stdout);
        va_end(ap);
    }
}

static double monoS(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static int64_t realNs(void)
{
    struct timespec t;
    clock_gettime(CLOCK_REALTIME, &t);
    return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

static int64_t stampNs(const builtin_interfaces_msg_dds__Time_* t)
{
    return (int64_t)t->sec * 1000000000 + (int64_t)t->nanosec;
}

/// The header of a scan or cloud: our frame id; nanosec < 1e9; stamped within kMaxStampAgeS of now; after the
/// previous sample of the same topic.
static void checkHeader(const char* what, const std_msgs_msg_dds__Header_* h, const char* frame, int64_t* lastNs)
{
    if (h->frame_id == NULL || strcmp(h->frame_id, frame) != 0) {
        fail("%s frame_id '%s', expected '%s'", what, h->frame_id ? h->frame_id : "(null)", frame);
    }
    if (h->stamp.nanosec >= 1000000000U) {
        fail("%s stamp nanosec %u >= 1e9", what, h->stamp.nanosec);
    }
    const int64_t ns = stampNs(&h->stamp);
    const double ageS = (double)(realNs() - ns) * 1e-9;
    if (!(fabs(ageS) < kMaxStampAgeS)) {
        fail("%s stamp %.3f s from now (the service is on this host)", what, ageS);
    }
    if (*lastNs != 0 && !(ns > *lastNs)) {
        fail("%s stamp does not advance: %lld after %lld", what, (long long)ns, (long long)*lastNs);
    }
    *lastNs = ns;
}

/// A frame as received: the scan's rays, the cloud's points and the sectors, matched by capture stamp.
typedef struct {
    int64_t stampNs;
    double firstSeenS;
    bool haveScan, haveClearScan, haveCloud, haveSectors, done;
    uint64_t sequence;
    int rays;
    float angleMin, angleIncrement, rangeMin, rangeMax;
    float ranges[kMaxRays];
    int clearRays; // the clearing scan: the same angles, range_max the clear range
    float clearRangeMin, clearRangeMax;
    float clearRanges[kMaxRays];
    int points;
    float xyz[kMaxRays][3];
    int sectors;
    float centreRad[kMaxRays];
    float sectorRange[kMaxRays];
    uint8_t state[kMaxRays], kind[kMaxRays];
} Frame;

static Frame ring[kRing];
static int ringNext = 0;

static Frame* frameAt(int64_t ns)
{
    for (int i = 0; i < kRing; ++i) {
        if (ring[i].stampNs == ns) {
            return &ring[i];
        }
    }
    Frame* f = &ring[ringNext];
    ringNext = (ringNext + 1) % kRing;
    memset(f, 0, sizeof *f);
    f->stampNs = ns;
    f->firstSeenS = monoS();
    return f;
}

typedef struct {
    long scans, clearScans, clouds, sectors, poseSamples;
    long clearRays, unknownRays, obstacleRays, points, cloudsWithPoints;
    long pairedScans, pairedClouds;
    long posesWritten, posesAccepted, posesOthers;
    double firstScanS, firstCloudS, matchedS, poseMatchedS;
    float rangeMax;
} Stats;

/// A LaserScan: the obstacle scan, or (`clearing`) the clearing scan, whose range_max must be the clear range.
static void checkScan(const sensor_msgs_msg_dds__LaserScan_* s, const Options* o, Stats* st, int64_t* lastNs,
                      bool clearing)
{
    checkHeader(clearing ? "clearing LaserScan" : "LaserScan", &s->header, o->frame, lastNs);
    const uint32_t n = s->ranges._length;
    if (n == 0 || n > kMaxRays) {
        fail("LaserScan with %u rays (1..%d: one per sector)", n, kMaxRays);
        return;
    }
    if (!(isfinite(s->angle_min) && isfinite(s->angle_max) && isfinite(s->angle_increment))) {
        fail("LaserScan angles not finite");
        return;
    }
    if (n > 1 && !(s->angle_increment > 0.0F && s->angle_min < s->angle_max)) {
        fail("LaserScan angles not increasing: min %g max %g increment %g", s->angle_min, s->angle_max,
             s->angle_increment);
    }
    const double last = (double)s->angle_min + (double)(n - 1) * s->angle_increment;
    if (fabs(last - s->angle_max) > kAngleTolRad) {
        fail("LaserScan angle_min + (n-1) x angle_increment = %.6f, angle_max %.6f (%u rays)", last, s->angle_max, n);
    }
    if (!(s->angle_min >= -M_PI && s->angle_max <= M_PI)) {
        fail("LaserScan angles outside [-pi, pi]: %g..%g", s->angle_min, s->angle_max);
    }
    if (s->intensities._length != 0 && s->intensities._length != n) {
        fail("LaserScan has %u intensities for %u rays", s->intensities._length, n);
    }
    if (s->time_increment != 0.0F) {
        fail("LaserScan time_increment %g: every ray of a global-shutter frame is taken at once", s->time_increment);
    }
    if (!(s->scan_time > 0.0F && s->scan_time <= 1.0F)) {
        fail("LaserScan scan_time %g s (the camera period)", s->scan_time);
    }
    if (!(isfinite(s->range_min) && isfinite(s->range_max) && s->range_min >= 0.0F && s->range_max > s->range_min)) {
        fail("LaserScan range_min %g range_max %g", s->range_min, s->range_max);
    }
    if (clearing && fabs(s->range_max - o->clearRangeM) > 1e-6) {
        fail("clearing LaserScan range_max %g m, expected the clear range %g m", s->range_max, o->clearRangeM);
    }
    for (uint32_t i = 0; i < n; ++i) {
        const float r = s->ranges._buffer[i];
        const bool valid =
            isnan(r) || (isinf(r) && r > 0.0F) || (isfinite(r) && r >= s->range_min && r <= s->range_max && r > 0.0F);
        if (!valid) {
            fail("LaserScan ray %u range %g: neither +inf (clear), NaN (unknown) nor in [range_min, range_max]", i, r);
        } else if (!clearing) {
            st->unknownRays += isnan(r) ? 1 : 0;
            st->clearRays += isinf(r) ? 1 : 0;
            st->obstacleRays += isfinite(r) ? 1 : 0;
        }
    }
    Frame* f = frameAt(stampNs(&s->header.stamp));
    if (clearing) {
        f->haveClearScan = true;
        f->clearRays = (int)n;
        f->clearRangeMin = s->range_min;
        f->clearRangeMax = s->range_max;
        memcpy(f->clearRanges, s->ranges._buffer, n * sizeof(float));
        if (f->haveScan &&
            (f->rays != (int)n || f->angleMin != s->angle_min || f->angleIncrement != s->angle_increment)) {
            fail("the clearing LaserScan's rays differ from the obstacle scan's of the same frame");
        }
        return;
    }
    st->rangeMax = s->range_max;
    f->haveScan = true;
    f->rays = (int)n;
    f->angleMin = s->angle_min;
    f->angleIncrement = s->angle_increment;
    f->rangeMin = s->range_min;
    f->rangeMax = s->range_max;
    memcpy(f->ranges, s->ranges._buffer, n * sizeof(float));
}

static void checkCloud(const sensor_msgs_msg_dds__PointCloud2_* c, const Options* o, Stats* st, int64_t* lastNs)
{
    static const char* names[3] = {"x", "y", "z"};
    checkHeader("PointCloud2", &c->header, o->frame, lastNs);
    if (c->fields._length != 3) {
        fail("PointCloud2 has %u fields, expected x, y, z", c->fields._length);
        return;
    }
    for (uint32_t i = 0; i < 3; ++i) {
        const sensor_msgs_msg_dds__PointField_* p = &c->fields._buffer[i];
        if (p->name == NULL || strcmp(p->name, names[i]) != 0 || p->offset != 4 * i || p->datatype != kFloat32 ||
            p->count != 1) {
            fail("PointCloud2 field %u: '%s' offset %u datatype %u count %u, expected '%s' %u FLOAT32 (%d) 1", i,
                 p->name ? p->name : "(null)", p->offset, p->datatype, p->count, names[i], 4 * i, kFloat32);
        }
    }
    if (c->height != 1 || c->point_step != kPointStep || c->row_step != c->width * kPointStep ||
        c->data._length != (uint64_t)c->row_step * c->height || c->is_bigendian || !c->is_dense) {
        fail("PointCloud2 layout: height %u width %u point_step %u row_step %u data %u bytes bigendian %d dense %d "
             "(expected height 1, point_step 12, row_step = width x 12, data = row_step, little-endian, dense)",
             c->height, c->width, c->point_step, c->row_step, c->data._length, c->is_bigendian, c->is_dense);
        return;
    }
    if (c->width > kMaxRays) {
        fail("PointCloud2 with %u points: more than one per sector", c->width);
        return;
    }
    Frame* f = frameAt(stampNs(&c->header.stamp));
    f->haveCloud = true;
    f->points = (int)c->width;
    for (uint32_t i = 0; i < c->width; ++i) {
        float p[3];
        memcpy(p, c->data._buffer + (size_t)i * kPointStep, sizeof p); // little-endian host, checked above
        if (!(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]))) {
            fail("PointCloud2 point %u not finite though is_dense", i);
        }
        if (!(p[2] <= -(float)o->minDepthM)) {
            fail("PointCloud2 point %u z = %g: a drop must lie at least obstacles.min_depth_m (%g) below the ground", i,
                 p[2], o->minDepthM);
        }
        memcpy(f->xyz[i], p, sizeof p);
        if (o->verbose) {
            printf("cloud %lld point %u: %.3f %.3f %.3f\n", (long long)stampNs(&c->header.stamp), i, p[0], p[1], p[2]);
        }
    }
    st->points += c->width;
    st->cloudsWithPoints += c->width > 0 ? 1 : 0;
}

static void checkSectors(const ugvsense_msg_ObstacleSectors* s, const Options* o, Stats* st)
{
    if (strcmp(s->vehicle, o->vehicle) != 0) {
        fail("ugvsense/sectors from vehicle '%s', expected '%s'", s->vehicle, o->vehicle);
        return;
    }
    if (s->pose_valid && !s->pose_stale && strcmp(s->pose.vehicle, o->vehicle) == 0 &&
        s->pose.east_m == kPoseMarkerEastM && s->pose.north_m == kPoseMarkerNorthM &&
        s->pose.heading_deg == kPoseHeadingDeg) {
        ++st->posesAccepted;
    } else if (s->pose_valid) {
        ++st->posesOthers;
    }
    const uint32_t n = s->sectors._length;
    if (n == 0 || n > kMaxRays) {
        fail("ugvsense/sectors with %u sectors", n);
        return;
    }
    // ObstacleSectors' capture stamp is the scan's and the cloud's header stamp (DdsBridge::onFrame).
    Frame* f = frameAt(s->capture_stamp_ns);
    f->haveSectors = true;
    f->sequence = s->sequence_number;
    f->sectors = (int)n;
    for (uint32_t i = 0; i < n; ++i) {
        const ugvsense_msg_Sector* x = &s->sectors._buffer[i];
        f->centreRad[i] = (float)(0.5 * ((double)x->bearing_min_deg + x->bearing_max_deg) * M_PI / 180.0);
        f->sectorRange[i] = x->range_m;
        f->state[i] = x->state;
        f->kind[i] = x->kind;
    }
}

/// The scan against the sectors of its frame: a ray per sector at its centre bearing; Clear -> +inf, Unknown ->
/// NaN, Obstacle -> the sector's range. Each cloud point on the ray of a negative obstacle sector, at its range.
static void checkSemantics(const Frame* f)
{
    if (f->sectors != f->rays || f->clearRays != f->rays) {
        fail("frame %lld: %d rays, %d clearing rays for %d sectors", (long long)f->stampNs, f->rays, f->clearRays,
             f->sectors);
        return;
    }
    for (int i = 0; i < f->rays; ++i) {
        const double angle = (double)f->angleMin + i * (double)f->angleIncrement;
        if (fabs(angle - f->centreRad[i]) > kAngleTolRad) {
            fail("ray %d at %.5f rad, its sector's centre at %.5f rad (sectors not evenly spaced?)", i, angle,
                 f->centreRad[i]);
        }
        const float r = f->ranges[i];
        const bool ok = f->state[i] == 1   ? isinf(r) && r > 0.0F
                        : f->state[i] == 0 ? isnan(r)
                        : f->state[i] == 2 ? r == f->sectorRange[i]
                                           : false;
        if (!ok) {
            fail("ray %d range %g for a sector of state %u (0 unknown -> NaN, 1 clear -> +inf, 2 obstacle -> %g)", i, r,
                 f->state[i], f->sectorRange[i]);
        }
        // The clearing scan: the same, but nothing within range_max (+inf) for an obstacle at or beyond it.
        const float c = f->clearRanges[i];
        const bool farObstacle = f->state[i] == 2 && f->sectorRange[i] >= f->clearRangeMax;
        const bool clearOk = f->state[i] == 1 || farObstacle ? isinf(c) && c > 0.0F
                             : f->state[i] == 0              ? isnan(c)
                             : f->state[i] == 2              ? c == f->sectorRange[i]
                                                             : false;
        if (f->haveClearScan && !clearOk) {
            fail("clearing ray %d range %g for a sector of state %u, range %g (range_max %g: an obstacle at or beyond "
                 "it is +inf)",
                 i, c, f->state[i], f->sectorRange[i], f->clearRangeMax);
        }
    }
    int negatives = 0;
    for (int i = 0; i < f->sectors; ++i) {
        negatives += f->state[i] == 2 && f->kind[i] == 2 ? 1 : 0;
    }
    if (negatives != f->points) {
        fail("frame %llu: %d negative obstacle sectors, %d cloud points (one per sector)",
             (unsigned long long)f->sequence, negatives, f->points);
    }
    for (int p = 0; p < f->points; ++p) {
        const double b = atan2(f->xyz[p][1], f->xyz[p][0]);
        const double h = hypot(f->xyz[p][0], f->xyz[p][1]);
        const long i = f->angleIncrement > 0.0F ? lround((b - f->angleMin) / f->angleIncrement) : 0;
        if (i < 0 || i >= f->rays || fabs(f->angleMin + i * (double)f->angleIncrement - b) > kAngleTolRad) {
            fail("cloud point %d at bearing %.5f rad lies on no ray", p, b);
            continue;
        }
        if (f->state[i] != 2 || f->kind[i] != 2 || fabs(h - f->ranges[i]) > kRangeTolM) {
            fail("cloud point %d (range %.3f m) on ray %ld of range %g, sector state %u kind %u: expected a negative "
                 "obstacle sector at the point's range",
                 p, h, i, f->ranges[i], f->state[i], f->kind[i]);
        }
    }
}

// ---- the course's truth ----------------------------------------------------------------------------------------

/// The ego pose of each frame of the replayed course (ugvsense sim --course writes REC.ugvrec.truth.csv). The
/// replay continues the frame sequence across loops, so frame = sequence_number mod count.
typedef struct {
    int count;
    double x[kMaxCourseFrames], y[kMaxCourseFrames], yawDeg[kMaxCourseFrames];
} Truth;

static Truth truth;

static bool loadTruth(const char* path)
{
    FILE* in = fopen(path, "r");
    if (in == NULL) {
        fprintf(stderr, "cyclone_interop: cannot read %s\n", path);
        return false;
    }
    char line[512];
    while (fgets(line, sizeof line, in) != NULL) {
        long k = 0;
        double t = 0.0, x = 0.0, y = 0.0, yaw = 0.0;
        if (sscanf(line, "%ld,%lf,%lf,%lf,%lf", &k, &t, &x, &y, &yaw) != 5 || k < 0 || k >= kMaxCourseFrames) {
            continue; // the header
        }
        truth.x[k] = x;
        truth.y[k] = y;
        truth.yawDeg[k] = yaw;
        truth.count = k + 1 > truth.count ? (int)k + 1 : truth.count;
    }
    fclose(in);
    return truth.count > 0;
}

/// The course's drop under a published point of frame `sequence`, or NULL.
static Drop* dropAt(Options* o, uint64_t sequence, double x, double y, double* wx, double* wy)
{
    const int k = (int)(sequence % (uint64_t)truth.count);
    const double yaw = truth.yawDeg[k] * M_PI / 180.0;
    *wx = truth.x[k] + cos(yaw) * x - sin(yaw) * y;
    *wy = truth.y[k] + sin(yaw) * x + cos(yaw) * y;
    for (int i = 0; i < o->dropCount; ++i) {
        Drop* d = &o->drops[i];
        if (fabs(*wx - d->x) <= d->halfX + kDropMarginM && fabs(*wy - d->y) <= d->halfY + kDropMarginM) {
            return d;
        }
    }
    return NULL;
}

// ---- the Nav2 consumer -----------------------------------------------------------------------------------------

enum { kUnknown = 0, kFree = 1, kLethal = 2 };

typedef struct {
    int nx, ny;
    uint8_t* cells;
    long marked, clearedBeyond, unmarkedPoints, markedPoints;
    long dropSourceZ, dropLayerZ, dropRange;
    double farthestClearedM;
    double farthestMarkedPointM;
} Grid;

static bool cellOf(const Grid* g, double x, double y, int* cx, int* cy)
{
    *cx = (int)floor((x - kGridMinX) / kCellM);
    *cy = (int)floor((y + kGridHalfY) / kCellM);
    return *cx >= 0 && *cy >= 0 && *cx < g->nx && *cy < g->ny;
}

static double cellCentreDistance(int cx, int cy)
{
    return hypot(kGridMinX + (cx + 0.5) * kCellM, -kGridHalfY + (cy + 0.5) * kCellM);
}

/// Clears the cells of the line from the origin to (x, y), end cell included (costmap_2d raytraceLine, Bresenham).
static void clearLine(Grid* g, double x, double y, double clearRangeM)
{
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    if (!cellOf(g, 0.0, 0.0, &x0, &y0) || !cellOf(g, x, y, &x1, &y1)) {
        return; // Nav2 cuts the ray at the map's edge; ours holds every ray up to 50 m
    }
    const int dx = abs(x1 - x0), dy = -abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    const double tolerance = kCellM * M_SQRT1_2; // the end cell's centre may lie half a diagonal beyond the end
    for (;;) {
        g->cells[(size_t)y0 * g->nx + x0] = kFree;
        const double d = cellCentreDistance(x0, y0);
        if (d > g->farthestClearedM) {
            g->farthestClearedM = d;
        }
        if (d > clearRangeM + tolerance) {
            ++g->clearedBeyond;
        }
        if (x0 == x1 && y0 == y1) {
            break;
        }
        const int e2 = 2 * err;
        if (e2 >= dy) {
            err += dy;
            x0 += sx;
        }
        if (e2 <= dx) {
            err += dx;
            y0 += sy;
        }
    }
}

/// ObservationBuffer (per-source z) + ObstacleLayer::updateBounds (layer z, 3-D range): whether a point marks, and
/// if not, why (counted).
static bool marks(Grid* g, const Nav2Layer* n, const Nav2Source* s, double x, double y, double z, bool count)
{
    if (!(z >= s->minObstacleHeight && z <= s->maxObstacleHeight)) {
        g->dropSourceZ += count ? 1 : 0;
        return false;
    }
    if (z < n->minObstacleHeight || z > n->maxObstacleHeight) {
        g->dropLayerZ += count ? 1 : 0;
        return false;
    }
    const double sq = x * x + y * y + z * z; // the sensor origin is the frame's origin (z = 0: on the ground)
    if (sq >= s->obstacleMaxRange * s->obstacleMaxRange || sq < s->obstacleMinRange * s->obstacleMinRange) {
        g->dropRange += count ? 1 : 0;
        return false;
    }
    return true;
}

static void mark(Grid* g, double x, double y)
{
    int cx = 0, cy = 0;
    if (cellOf(g, x, y, &cx, &cy)) {
        g->cells[(size_t)cy * g->nx + cx] = kLethal;
        ++g->marked;
    }
}

/// Ray i of the obstacle scan, or (`clearing`) of the clearing scan, as laser_geometry projects it for Nav2: +inf ->
/// range_max - epsilon when inf_is_valid; points kept when range_min <= r < range_max (NaN and the rest dropped).
/// Returns false for a dropped ray.
static bool projectRay(const Frame* f, bool clearing, const Nav2Source* s, int i, double* x, double* y)
{
    const float rangeMin = clearing ? f->clearRangeMin : f->rangeMin;
    const float rangeMax = clearing ? f->clearRangeMax : f->rangeMax;
    double r = clearing ? f->clearRanges[i] : f->ranges[i];
    if (s->infIsValid && isinf(r) && r > 0.0) {
        r = rangeMax - kNav2InfEpsilon;
    }
    if (!(r >= rangeMin && r < rangeMax)) {
        return false;
    }
    const double a = (double)f->angleMin + i * (double)f->angleIncrement;
    *x = r * cos(a);
    *y = r * sin(a);
    return true;
}

/// A scan source's clearing: each projected ray raytraced, cut to raytrace_max_range.
static void clearAlong(Grid* g, const Frame* f, bool clearing, const Nav2Source* s, double clearRangeM)
{
    for (int i = 0; i < f->rays; ++i) {
        double x = 0.0, y = 0.0;
        if (!projectRay(f, clearing, s, i, &x, &y)) {
            continue;
        }
        const double len = hypot(x, y);
        if (len < s->raytraceMinRange) {
            continue;
        }
        const double scale = len > s->raytraceMaxRange ? s->raytraceMaxRange / len : 1.0;
        clearLine(g, x * scale, y * scale, clearRangeM);
    }
}

/// A scan source's marking: each projected ray's end that passes the height and range rules.
static void markAlong(Grid* g, const Nav2Layer* n, const Frame* f, bool clearing, const Nav2Source* s)
{
    for (int i = 0; i < f->rays; ++i) {
        double x = 0.0, y = 0.0;
        if (projectRay(f, clearing, s, i, &x, &y) && marks(g, n, s, x, y, 0.0, false)) {
            mark(g, x, y);
        }
    }
}

/// One costmap update with this frame's observations, in Nav2's order: every clearing observation raytraced,
/// then every marking one marked. The grid persists across frames (the vehicle's motion between frames is
/// ignored: at most 0.15 m).
static void nav2Update(Grid* g, Options* o, const Frame* f)
{
    const Nav2Layer* n = &o->nav2;
    const double clearRangeM = o->clearRangeM;
    if (n->scan.clearing) {
        clearAlong(g, f, false, &n->scan, clearRangeM);
    }
    if (n->clear.present && n->clear.clearing) {
        clearAlong(g, f, true, &n->clear, clearRangeM);
    }
    if (n->scan.marking) {
        markAlong(g, n, f, false, &n->scan);
    }
    if (n->clear.present && n->clear.marking) {
        markAlong(g, n, f, true, &n->clear);
    }
    // A point counts as marked when the negatives source itself marks it: the scan's ray of the same sector marks
    // the drop's rim too (within its obstacle_max_range), but that does not make the cloud's settings right.
    for (int p = 0; p < f->points; ++p) {
        const double x = f->xyz[p][0], y = f->xyz[p][1], z = f->xyz[p][2];
        int cx = 0, cy = 0;
        const bool marked =
            n->negatives.marking && marks(g, n, &n->negatives, x, y, z, true) && cellOf(g, x, y, &cx, &cy);
        if (marked) {
            mark(g, x, y);
            ++g->markedPoints;
            const double d = hypot(x, y);
            g->farthestMarkedPointM = d > g->farthestMarkedPointM ? d : g->farthestMarkedPointM;
        } else {
            ++g->unmarkedPoints;
        }
        if (o->dropCount > 0 && truth.count > 0 && f->haveSectors) {
            double wx = 0.0, wy = 0.0;
            Drop* d = dropAt(o, f->sequence, x, y, &wx, &wy);
            if (d == NULL) {
                fail("a drop point of frame %d at (%.2f, %.2f) m in the course lies on none of its drops",
                     (int)(f->sequence % (uint64_t)truth.count), wx, wy);
            } else {
                ++d->points;
                d->marked += marked ? 1 : 0;
            }
        }
    }
}

// ---- DDS -------------------------------------------------------------------------------------------------------

static dds_entity_t makeReader(dds_entity_t pp, const dds_topic_descriptor_t* desc, const char* name, bool reliable)
{
    const dds_entity_t topic = dds_create_topic(pp, desc, name, NULL, NULL);
    if (topic < 0) {
        fprintf(stderr, "cyclone_interop: topic %s: %s\n", name, dds_strretcode(topic));
        return topic;
    }
    dds_qos_t* q = dds_create_qos();
    dds_qset_reliability(q, reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT, DDS_MSECS(100));
    dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, kMaxSamples);
    const dds_entity_t r = dds_create_reader(pp, topic, q, NULL);
    dds_delete_qos(q);
    if (r < 0) {
        fprintf(stderr, "cyclone_interop: reader %s: %s\n", name, dds_strretcode(r));
    }
    return r;
}

/// The service's writer matched to `reader`: its type name and, for the ROS topics, the reliability it offers.
static bool matchedWriter(dds_entity_t reader, const char* what, const char* typeName, bool wantReliable,
                          dds_guid_t* participant)
{
    dds_instance_handle_t h[4];
    const dds_return_t n = dds_get_matched_publications(reader, h, 4);
    if (n <= 0) {
        return false;
    }
    dds_builtintopic_endpoint_t* e = dds_get_matched_publication_data(reader, h[0]);
    if (e == NULL) {
        return false;
    }
    if (strcmp(e->type_name, typeName) != 0) {
        fail("%s: the service's writer has type '%s', expected '%s'", what, e->type_name, typeName);
    }
    dds_reliability_kind_t kind = DDS_RELIABILITY_BEST_EFFORT;
    dds_duration_t blocking = 0;
    if (wantReliable && !(dds_qget_reliability(e->qos, &kind, &blocking) && kind == DDS_RELIABILITY_RELIABLE)) {
        fail("%s: the service's writer is not reliable (dds.ros_reliability: reliable is the default)", what);
    }
    printf("discovered %s writer '%s' %s (%s)\n", what, e->topic_name, e->type_name,
           kind == DDS_RELIABILITY_RELIABLE ? "reliable" : "best effort");
    if (participant != NULL) {
        *participant = e->participant_key;
    }
    dds_builtintopic_free_endpoint(e);
    return true;
}

/// The name (Fast DDS: the participant QoS's name, sent as PID_ENTITY_NAME) of the participant `key` as Cyclone
/// discovered it; false while it is not known.
static bool participantName(dds_entity_t builtinReader, const dds_guid_t* key, char* out, size_t size)
{
    void* samples[kMaxSamples] = {NULL};
    dds_sample_info_t infos[kMaxSamples];
    const dds_return_t n = dds_read(builtinReader, samples, infos, kMaxSamples, kMaxSamples);
    bool found = false;
    for (dds_return_t i = 0; i < n && !found; ++i) {
        const dds_builtintopic_participant_t* p = samples[i];
        char* name = NULL;
        if (infos[i].valid_data && memcmp(&p->key, key, sizeof *key) == 0) {
            found = true;
            snprintf(out, size, "%s", dds_qget_entity_name(p->qos, &name) && name != NULL ? name : "");
            dds_free(name);
        }
    }
    if (n > 0) {
        dds_return_loan(builtinReader, samples, n);
    }
    return found;
}

static void writePose(dds_entity_t writer, const Options* o, Stats* st)
{
    ugvsense_msg_VehiclePose p;
    memset(&p, 0, sizeof p);
    snprintf(p.vehicle, sizeof p.vehicle, "%s", o->vehicle);
    p.stamp_ns = realNs();
    p.latitude_deg = -34.9285; // Adelaide, as bus-send --poses
    p.longitude_deg = 138.6007;
    p.altitude_m = 50.0;
    p.east_m = kPoseMarkerEastM;
    p.north_m = kPoseMarkerNorthM;
    p.up_m = 0.0;
    p.heading_deg = kPoseHeadingDeg;
    p.covariance[0] = 0.04; // 0.2 m, 0.2 m, 1 deg
    p.covariance[4] = 0.04;
    p.covariance[8] = 1.0;
    if (dds_write(writer, &p) == DDS_RETCODE_OK) {
        ++st->posesWritten;
    }
}

#define TAKE_EACH(reader, Type, body)                                                                                  \
    do {                                                                                                               \
        void* samples_[kMaxSamples] = {NULL};                                                                          \
        dds_sample_info_t infos_[kMaxSamples];                                                                         \
        const dds_return_t n_ = dds_take((reader), samples_, infos_, kMaxSamples, kMaxSamples);                        \
        for (dds_return_t k_ = 0; k_ < n_; ++k_) {                                                                     \
            if (infos_[k_].valid_data) {                                                                               \
                const Type* sample = (const Type*)samples_[k_];                                                        \
                body;                                                                                                  \
            }                                                                                                          \
        }                                                                                                              \
        if (n_ > 0) {                                                                                                  \
            dds_return_loan((reader), samples_, n_);                                                                   \
        }                                                                                                              \
    } while (0)

/// What the run found besides the per-sample checks and statistics.
typedef struct {
    char scanTopic[256], clearTopic[256], cloudTopic[256];
    bool scanMatched, clearMatched, cloudMatched, sectorsMatched, poseMatched;
    dds_guid_t serviceKey; ///< the participant of the scan's writer
    char serviceName[256];
    bool nameKnown;
    long frames;        ///< with both scans and a cloud: Nav2 updates
    long pairedSectors; ///< of those, checked against their sectors
} Run;

/// Every expectation that needs samples is met: the rest of the run would only repeat the checks.
static bool enough(const Options* o, const Stats* st, const Run* r)
{
    if (o->expectDenied || (o->participant != NULL && !r->nameKnown)) {
        return false;
    }
    for (int i = 0; i < o->dropCount; ++i) {
        if (o->drops[i].points == 0) {
            return false;
        }
    }
    const bool ours = usesOurTopics(o);
    return r->frames >= o->minFrames && (!ours || (r->pairedSectors > 0 && st->posesAccepted >= 3)) && st->points > 0 &&
           st->clearRays > 0 && st->obstacleRays > 0;
}

/// Discovery: the service's writers (their type names and QoS), its participant's name, its pose reader.
static void discover(dds_entity_t scans, dds_entity_t clearScans, dds_entity_t clouds, dds_entity_t sectors,
                     dds_entity_t poses, dds_entity_t participants, double sinceStartS, Stats* st, Run* r)
{
    if (!r->scanMatched &&
        (r->scanMatched = matchedWriter(scans, "LaserScan", sensor_msgs_msg_dds__LaserScan__desc.m_typename, true,
                                        &r->serviceKey))) {
        st->matchedS = sinceStartS;
    }
    if (r->scanMatched && !r->nameKnown && participants >= 0) {
        r->nameKnown = participantName(participants, &r->serviceKey, r->serviceName, sizeof r->serviceName);
    }
    if (!r->clearMatched) {
        r->clearMatched = matchedWriter(clearScans, "clearing LaserScan",
                                        sensor_msgs_msg_dds__LaserScan__desc.m_typename, true, NULL);
    }
    if (!r->cloudMatched) {
        r->cloudMatched =
            matchedWriter(clouds, "PointCloud2", sensor_msgs_msg_dds__PointCloud2__desc.m_typename, true, NULL);
    }
    if (!r->sectorsMatched && sectors > 0) {
        r->sectorsMatched =
            matchedWriter(sectors, "ObstacleSectors", ugvsense_msg_ObstacleSectors_desc.m_typename, false, NULL);
    }
    dds_publication_matched_status_t pm;
    if (!r->poseMatched && poses > 0 && dds_get_publication_matched_status(poses, &pm) == DDS_RETCODE_OK &&
        pm.current_count > 0) {
        r->poseMatched = true;
        st->poseMatchedS = sinceStartS;
        printf("discovered the service's ugvsense/pose reader\n");
    }
}

/// The frames whose two scans and cloud have arrived: checked against their sectors, then one Nav2 update each.
static void processFrames(Grid* g, Options* o, double now, Run* r)
{
    for (int i = 0; i < kRing; ++i) {
        Frame* f = &ring[i];
        // The three are written together (sectors first); give a lost best-effort sectors sample 0.5 s.
        if (f->done || !f->haveScan || !f->haveClearScan || !f->haveCloud ||
            (!f->haveSectors && now - f->firstSeenS < 0.5)) {
            continue;
        }
        // The sectors are best effort: a frame without them is still a Nav2 update.
        if (f->haveSectors) {
            checkSemantics(f);
            ++r->pairedSectors;
        }
        nav2Update(g, o, f);
        f->done = true;
        ++r->frames;
    }
}

static void printSummary(const Options* o, const Stats* st, const Grid* g, const Run* r)
{
    printf("discovery: writers matched after %.2f s, the pose reader after %.2f s; first scan after %.2f s, first "
           "cloud after %.2f s; the service's participant '%s'\n",
           st->matchedS, st->poseMatchedS, st->firstScanS, st->firstCloudS, r->serviceName);
    printf("received %ld LaserScan (%ld clear, %ld unknown, %ld obstacle rays), %ld clearing LaserScan, %ld "
           "PointCloud2 (%ld with points, %ld points), %ld ObstacleSectors; %ld frames with both scans and the cloud "
           "(%ld checked against their sectors)\n",
           st->scans, st->clearRays, st->unknownRays, st->obstacleRays, st->clearScans, st->clouds,
           st->cloudsWithPoints, st->points, st->sectors, r->frames, r->pairedSectors);
    printf("poses: %ld written, %ld sectors samples carry ours (valid, not stale), %ld carry another pose\n",
           st->posesWritten, st->posesAccepted, st->posesOthers);
    const Nav2Layer* n = &o->nav2;
    printf("Nav2 layer (min_obstacle_height %g, max %g; scan: marking %d clearing %d, inf_is_valid %d, "
           "obstacle_max_range %g, raytrace_max_range %g; clear: %s, marking %d clearing %d, inf_is_valid %d, "
           "raytrace_max_range %g; negatives: z in [%g, %g], obstacle_max_range %g): %ld of %ld negative points "
           "marked (farthest %.2f m), %ld dropped by the source's z limits, %ld by the layer's, %ld by "
           "obstacle_max_range; farthest cleared cell %.2f m (Clear guarantees %g m), %ld cell clearings beyond it\n",
           n->minObstacleHeight, n->maxObstacleHeight, n->scan.marking, n->scan.clearing, n->scan.infIsValid,
           n->scan.obstacleMaxRange, n->scan.raytraceMaxRange, n->clear.present ? "used" : "not a source",
           n->clear.marking, n->clear.clearing, n->clear.infIsValid, n->clear.raytraceMaxRange,
           n->negatives.minObstacleHeight, n->negatives.maxObstacleHeight, n->negatives.obstacleMaxRange,
           g->markedPoints, st->points, g->farthestMarkedPointM, g->dropSourceZ, g->dropLayerZ, g->dropRange,
           g->farthestClearedM, o->clearRangeM, g->clearedBeyond);
    if (n->scan.clearing && st->rangeMax > o->clearRangeM) {
        printf("note: a Clear ray reads as range_max = %g m to a consumer with inf_is_valid; only "
               "raytrace_max_range <= %g m keeps its clearing within what Clear guarantees\n",
               st->rangeMax, o->clearRangeM);
    }
    for (int i = 0; i < o->dropCount; ++i) {
        const Drop* d = &o->drops[i];
        printf("the course's %s at (%g, %g) m: %ld points published, %ld marked\n", d->name, d->x, d->y, d->points,
               d->marked);
    }
}

/// A Nav2 source's topic, if the README gives one, is the ROS 2 name of ours: /<ns>/<name> for rt/<ns>/<name>.
static bool sameRosTopic(const char* rosName, const char* ddsName)
{
    return rosName[0] == '\0' || (rosName[0] == '/' && strcmp(rosName + 1, ddsName + strlen("rt/")) == 0);
}

/// The expectations over the whole run (the per-sample checks failed as they went).
static void checkRun(const Options* o, const Stats* st, const Grid* g, const Run* r)
{
    for (int i = 0; i < o->dropCount; ++i) {
        const Drop* d = &o->drops[i];
        if (d->points == 0 || d->marked < d->points) {
            fail("the course's %s: %ld points published, %ld marked by the Nav2 layer's rules", d->name, d->points,
                 d->marked);
        }
    }
    if (o->participant != NULL && (!r->nameKnown || strcmp(r->serviceName, o->participant) != 0)) {
        fail("the scan's writer belongs to participant '%s', expected '%s'",
             r->nameKnown ? r->serviceName : "(unknown)", o->participant);
    }
    if (!r->scanMatched || !r->clearMatched || !r->cloudMatched) {
        fail("the service's scan, clearing scan or cloud writer was not discovered in %.0f s", o->durationS);
    }
    const bool ours = usesOurTopics(o);
    if (ours && !r->poseMatched) {
        fail("the service's ugvsense/pose reader was not discovered in %.0f s", o->durationS);
    }
    if (r->frames < o->minFrames) {
        fail("only %ld frames with both LaserScans and a PointCloud2 (at least %d)", r->frames, o->minFrames);
    }
    if (ours && r->pairedSectors < 1) {
        fail("no frame's scan could be checked against its ugvsense/sectors");
    }
    if (st->clearRays == 0 || st->obstacleRays == 0) {
        fail("the scans hold %ld clear and %ld obstacle rays: the default course has both", st->clearRays,
             st->obstacleRays);
    }
    if (st->points == 0) {
        fail("no negative obstacle point in %ld clouds: the default course has a hole ahead", st->clouds);
    }
    if (ours && st->posesAccepted < 3) {
        fail("only %ld ugvsense/sectors samples carry our pose (valid, not stale)", st->posesAccepted);
    }
    if (g->unmarkedPoints > 0) {
        fail("%ld of %ld negative obstacle points not marked by the Nav2 layer's rules", g->unmarkedPoints, st->points);
    }
    if (g->clearedBeyond > 0) {
        fail("%ld cell clearings beyond the %g m that Clear guarantees (farthest %.2f m)", g->clearedBeyond,
             o->clearRangeM, g->farthestClearedM);
    }
    if (!sameRosTopic(o->nav2.scan.topic, r->scanTopic)) {
        fail("the Nav2 scan source's topic '%s' is not /%s", o->nav2.scan.topic, r->scanTopic + strlen("rt/"));
    }
    if (!sameRosTopic(o->nav2.clear.topic, r->clearTopic)) {
        fail("the Nav2 clear source's topic '%s' is not /%s", o->nav2.clear.topic, r->clearTopic + strlen("rt/"));
    }
    if (!sameRosTopic(o->nav2.negatives.topic, r->cloudTopic)) {
        fail("the Nav2 negatives source's topic '%s' is not /%s", o->nav2.negatives.topic,
             r->cloudTopic + strlen("rt/"));
    }
}

/// The participant's QoS for an SROS2 enclave, property by property as rmw_cyclonedds_cpp (Humble, rmw_node.cpp)
/// sets them from ROS_SECURITY_ENCLAVE: the three plugins of Cyclone DDS and the enclave's six files; its user data
/// names the enclave as ROS 2's does.
static dds_qos_t* enclaveQos(const char* enclave)
{
    static const char* const plugins[][3] = {{"auth", "dds_security_auth", "authentication"},
                                             {"crypto", "dds_security_crypto", "crypto"},
                                             {"access", "dds_security_ac", "access_control"}};
    static const char* const files[][2] = {{"dds.sec.auth.identity_ca", "identity_ca.cert.pem"},
                                           {"dds.sec.auth.identity_certificate", "cert.pem"},
                                           {"dds.sec.auth.private_key", "key.pem"},
                                           {"dds.sec.access.permissions_ca", "permissions_ca.cert.pem"},
                                           {"dds.sec.access.governance", "governance.p7s"},
                                           {"dds.sec.access.permissions", "permissions.p7s"}};
    dds_qos_t* q = dds_create_qos();
    char name[64], value[4096];
    for (size_t i = 0; i < sizeof plugins / sizeof plugins[0]; ++i) {
        snprintf(name, sizeof name, "dds.sec.%s.library.path", plugins[i][0]);
        dds_qset_prop(q, name, plugins[i][1]);
        snprintf(name, sizeof name, "dds.sec.%s.library.init", plugins[i][0]);
        snprintf(value, sizeof value, "init_%s", plugins[i][2]);
        dds_qset_prop(q, name, value);
        snprintf(name, sizeof name, "dds.sec.%s.library.finalize", plugins[i][0]);
        snprintf(value, sizeof value, "finalize_%s", plugins[i][2]);
        dds_qset_prop(q, name, value);
    }
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        snprintf(value, sizeof value, "file:%s/%s", enclave, files[i][1]);
        dds_qset_prop(q, files[i][0], value);
    }
    const char* base = strrchr(enclave, '/');
    snprintf(value, sizeof value, "enclave=/%s;", base != NULL ? base + 1 : enclave);
    dds_qset_userdata(q, value, strlen(value));
    return q;
}

/// --expect-denied: the whole run saw nothing of the service.
static int checkDenied(const Options* o, const Stats* st, const Run* r)
{
    const long samples = st->scans + st->clearScans + st->clouds + st->sectors;
    const bool matched = r->scanMatched || r->clearMatched || r->cloudMatched || r->sectorsMatched || r->poseMatched;
    printf("%s for %.0f s: %ld samples received (%ld LaserScan, %ld clearing LaserScan, %ld PointCloud2, %ld "
           "ObstacleSectors), %s; %ld poses written\n",
           o->enclave != NULL ? "with another CA's enclave" : "without a certificate", o->durationS, samples, st->scans,
           st->clearScans, st->clouds, st->sectors,
           matched ? "a writer or reader of the service matched" : "nothing of the service matched", st->posesWritten);
    if (samples > 0 || matched) {
        printf("FAIL: a participant without a valid certificate saw the secured service\n");
        return 1;
    }
    printf("OK: denied: nothing of the secured service was discovered or received\n");
    return 0;
}

int main(int argc, char** argv)
{
    Options o;
    if (!parseOptions(argc, argv, &o) || (o.truthPath != NULL && !loadTruth(o.truthPath))) {
        return 2;
    }
    Run r;
    memset(&r, 0, sizeof r);
    snprintf(r.scanTopic, sizeof r.scanTopic, "rt/%s/obstacle_scan", o.ns);
    snprintf(r.clearTopic, sizeof r.clearTopic, "rt/%s/clear_scan", o.ns);
    snprintf(r.cloudTopic, sizeof r.cloudTopic, "rt/%s/negative_obstacles", o.ns);
    Grid g = {0};
    g.nx = (int)ceil((kGridMaxX - kGridMinX) / kCellM);
    g.ny = (int)ceil(2.0 * kGridHalfY / kCellM);
    g.cells = calloc((size_t)g.nx * g.ny, 1);
    if (g.cells == NULL) {
        return 2;
    }

    const double t0 = monoS();
    dds_qos_t* ppQos = o.enclave != NULL ? enclaveQos(o.enclave) : NULL;
    const dds_entity_t pp = dds_create_participant((dds_domainid_t)o.domain, ppQos, NULL);
    dds_delete_qos(ppQos);
    if (pp < 0 && o.expectDenied) {
        printf("OK: denied: the participant could not even be created (%s)\n", dds_strretcode(pp));
        return 0;
    }
    if (pp < 0) {
        fprintf(stderr, "cyclone_interop: participant on domain %d: %s\n", o.domain, dds_strretcode(pp));
        return 2;
    }
    const bool reliable = !o.bestEffort;
    const dds_entity_t scans = makeReader(pp, &sensor_msgs_msg_dds__LaserScan__desc, r.scanTopic, reliable);
    const dds_entity_t clearScans = makeReader(pp, &sensor_msgs_msg_dds__LaserScan__desc, r.clearTopic, reliable);
    const dds_entity_t clouds = makeReader(pp, &sensor_msgs_msg_dds__PointCloud2__desc, r.cloudTopic, reliable);
    // ugvsense/sectors read best effort, as our own readers do (its writer is reliable: either kind matches). 0 stands
    // for "not made".
    const bool ours = usesOurTopics(&o);
    const dds_entity_t sectors =
        ours ? makeReader(pp, &ugvsense_msg_ObstacleSectors_desc, "ugvsense/sectors", false) : 0;
    const dds_entity_t poseTopic =
        ours ? dds_create_topic(pp, &ugvsense_msg_VehiclePose_desc, "ugvsense/pose", NULL, NULL) : 0;
    const dds_entity_t poses = poseTopic <= 0 ? poseTopic : dds_create_writer(pp, poseTopic, NULL, NULL);
    const dds_entity_t participants = dds_create_reader(pp, DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, NULL, NULL);
    if (scans < 0 || clearScans < 0 || clouds < 0 || sectors < 0 || poses < 0) {
        dds_delete(pp);
        return 2;
    }
    const dds_entity_t ws = dds_create_waitset(pp);
    dds_waitset_attach(ws, dds_create_readcondition(scans, DDS_ANY_STATE), 0);
    dds_waitset_attach(ws, dds_create_readcondition(clearScans, DDS_ANY_STATE), 0);
    dds_waitset_attach(ws, dds_create_readcondition(clouds, DDS_ANY_STATE), 0);
    if (ours) {
        dds_waitset_attach(ws, dds_create_readcondition(sectors, DDS_ANY_STATE), 0);
    }

    Stats st = {0};
    int64_t lastScanNs = 0, lastClearNs = 0, lastCloudNs = 0;
    double nextPoseS = t0;
    for (double now = t0; now - t0 < o.durationS && !(now - t0 >= o.minDurationS && enough(&o, &st, &r));
         now = monoS()) {
        if (ours && now >= nextPoseS) {
            writePose(poses, &o, &st);
            nextPoseS += 0.1;
        }
        discover(scans, clearScans, clouds, sectors, poses, participants, now - t0, &st, &r);
        dds_waitset_wait(ws, NULL, 0, DDS_MSECS(20));
        TAKE_EACH(scans, sensor_msgs_msg_dds__LaserScan_, {
            if (st.scans++ == 0) {
                st.firstScanS = monoS() - t0;
            }
            checkScan(sample, &o, &st, &lastScanNs, false);
        });
        TAKE_EACH(clearScans, sensor_msgs_msg_dds__LaserScan_, {
            ++st.clearScans;
            checkScan(sample, &o, &st, &lastClearNs, true);
        });
        TAKE_EACH(clouds, sensor_msgs_msg_dds__PointCloud2_, {
            if (st.clouds++ == 0) {
                st.firstCloudS = monoS() - t0;
            }
            checkCloud(sample, &o, &st, &lastCloudNs);
        });
        if (ours) {
            TAKE_EACH(sectors, ugvsense_msg_ObstacleSectors, {
                ++st.sectors;
                checkSectors(sample, &o, &st);
            });
        }
        processFrames(&g, &o, now, &r);
    }
    dds_delete(pp);
    if (o.expectDenied) {
        free(g.cells);
        return checkDenied(&o, &st, &r);
    }

    printSummary(&o, &st, &g, &r);
    checkRun(&o, &st, &g, &r);
    free(g.cells);
    if (failures > 0) {
        printf("FAIL: %d check(s) failed\n", failures);
        return 1;
    }
    printf("OK: Cyclone DDS%s read the service's two LaserScans and PointCloud2%s, and a Nav2 layer marks every "
           "negative obstacle and clears nothing beyond %g m\n",
           o.enclave != NULL ? " (a ROS 2 node's enclave on the secured bus)" : "",
           o.enclave != NULL ? "" : ", wrote a pose it used", o.clearRangeM);
    return 0;
}
