#include "ugv/service/correlator_task.hpp"

#include <algorithm>
#include <filesystem>

#include "ugv/adapters/correlate_io.hpp"
#include "ugv/adapters/correlator_dds.hpp"
#include "ugv/ipc/dds_convert.hpp"
#include "ugv/platform/clock.hpp"
#include "ugv/platform/log.hpp"

namespace ugv::service {

namespace {

namespace fs = std::filesystem;
namespace msg = ipc::dds::msg;

constexpr std::uint64_t kMaxWarnings = 20; ///< warnings reported one by one; the rest are only counted

/// Opens DIR/NAME.jsonl for writing; an existing one is first renamed NAME.N.jsonl (the lowest free N).
Result<void, Error> openLog(const std::string& dir, const std::string& name, std::ofstream& out)
{
    std::error_code ec;
    fs::create_directories(dir, ec);
    const fs::path path = fs::path(dir) / (name + ".jsonl");
    if (fs::exists(path)) {
        for (int n = 1;; ++n) {
            const fs::path kept = fs::path(dir) / (name + "." + std::to_string(n) + ".jsonl");
            if (!fs::exists(kept)) {
                fs::rename(path, kept, ec);
                break;
            }
        }
    }
    out.open(path);
    if (!out) {
        return Unexpected(Error{path.string(), "cannot create the correlator log",
                                "check correlator.log_dir: the folder must be writable by the service"});
    }
    return {};
}

std::string senderOf(const msg::OoiObservation& s)
{
    return s.ugv().to_string();
}
std::string senderOf(const msg::UavObservation& s)
{
    return "uav:" + s.source().to_string();
}
std::string senderOf(const msg::ConfirmationState& s)
{
    return "confirm:" + s.source().to_string();
}
std::string senderOf(const msg::PoseCorrection& s)
{
    return "correction:" + s.source().to_string();
}

} // namespace

LiveCorrelator::LiveCorrelator(const LiveCorrelatorOptions& options)
    : options_(options), feed_(options.mode, options.periodS, options.lateWindowS)
{
}

Result<std::unique_ptr<LiveCorrelator>, Error> LiveCorrelator::create(ipc::dds::Bus& bus,
                                                                      const LiveCorrelatorOptions& options)
{
    if (!(options.periodS > 0.0) || !(options.reorderMs >= 0.0) || !(options.startupHoldMs >= 0.0) ||
        !(options.maxRatePerSource > 0.0) || !(options.maxClockSkewMs >= 0.0) || !(options.lateWindowS >= 0.0)) {
        return Unexpected(Error{"correlator", "period, reorder time, late window, rate or clock skew out of range",
                                "period_s > 0, reorder_ms >= 0, late_window_s >= 0, max_rate_per_source > 0, "
                                "max_clock_skew_ms >= 0"});
    }
    std::unique_ptr<LiveCorrelator> c(new LiveCorrelator(options));
    c->securedBus_ = bus.config().security.enabled ? &bus : nullptr;
    auto obs = bus.reader<msg::OoiObservation>();
    auto uav = bus.reader<msg::UavObservation>();
    auto confirm = bus.reader<msg::ConfirmationState>();
    auto corrections = bus.reader<msg::PoseCorrection>();
    if (!obs || !uav || !confirm || !corrections) {
        return Unexpected(!obs ? obs.error() : !uav ? uav.error() : !confirm ? confirm.error() : corrections.error());
    }
    c->observations_ = *obs;
    c->uav_ = *uav;
    c->confirmations_ = *confirm;
    c->corrections_ = *corrections;
    if (options.publish) {
        auto out = bus.writer<msg::CorrelatedOoiList>();
        if (!out) {
            return Unexpected(out.error());
        }
        c->out_ = *out;
    }
    if (!options.logDir.empty()) {
        if (auto ok = openLog(options.logDir, "inputs", c->inputsLog_); !ok) {
            return Unexpected(ok.error());
        }
        if (auto ok = openLog(options.logDir, "snapshots", c->snapshotsLog_); !ok) {
            return Unexpected(ok.error());
        }
    }
    return c;
}

void LiveCorrelator::warn(const std::string& text)
{
    if (++warned_ <= kMaxWarnings) {
        warnings_.push_back(text);
    } else if (warned_ == kMaxWarnings + 1) {
        warnings_.push_back("correlator: more refused inputs are only counted (see the stats)");
    }
}

void LiveCorrelator::warnOnce(const std::string& text)
{
    warnings_.push_back(text);
}

std::vector<std::string> LiveCorrelator::takeWarnings()
{
    std::vector<std::string> out;
    out.swap(warnings_);
    return out;
}

bool LiveCorrelator::admit(const std::string& sender, std::uint64_t sequence,
                           const eprosima::fastdds::dds::SampleInfo& info)
{
    std::uint64_t& highest = highestSeq_[sender];
    if (sequence <= highest) {
        ++stats_.duplicates;
        return false;
    }
    // Token bucket over source timestamps, per participant.
    const auto& prefix = info.sample_identity.writer_guid().guidPrefix;
    const std::string participant(reinterpret_cast<const char*>(prefix.value), sizeof(prefix.value));
    Bucket& b = buckets_[participant];
    const std::int64_t sourceNs = info.source_timestamp.to_ns();
    const std::int64_t aheadNs = sourceNs - ipc::dds::realtimeNowNs();
    if (static_cast<double>(aheadNs) > options_.maxClockSkewMs * 1e6) {
        ++stats_.flooded;
        if (++stats_.aheadOfClock == 1) {
            warnOnce("correlator: '" + sender + "' stamps its samples " + std::to_string(aheadNs / 1'000'000) +
                     " ms ahead of this host's clock, more than correlator.max_clock_skew_ms (" +
                     std::to_string(options_.maxClockSkewMs) +
                     "): they are refused and counted; synchronise the hosts' clocks (chrony) or raise the skew");
        }
        return false; // not marked as seen, as below
    }
    if (b.lastSourceNs == 0) {
        b.tokens = options_.maxRatePerSource;
    } else if (sourceNs > b.lastSourceNs) {
        b.tokens = std::min(options_.maxRatePerSource, b.tokens + static_cast<double>(sourceNs - b.lastSourceNs) *
                                                                      1e-9 * options_.maxRatePerSource);
    }
    b.lastSourceNs = std::max(b.lastSourceNs, sourceNs);
    if (b.tokens < 1.0) {
        ++stats_.flooded;
        if (stats_.flooded == 1) {
            warnOnce("correlator: '" + sender + "' sends faster than correlator.max_rate_per_source (" +
                     std::to_string(options_.maxRatePerSource) + "/s): inputs beyond it are refused and counted");
        }
        return false; // not marked as seen: a repaired resend can still come in
    }
    b.tokens -= 1.0;
    highest = sequence;
    return true;
}

bool LiveCorrelator::sentByItsOwner(const std::string& name, ipc::dds::TopicId topic,
                                    const eprosima::fastdds::dds::SampleInfo& info)
{
    if (securedBus_ == nullptr) {
        return true;
    }
    const std::string writer = securedBus_->writerIdentity(info);
    if (writer == name) {
        return true;
    }
    ++stats_.impersonated;
    warn("correlator: refused: " + ipc::dds::topicName(topic, securedBus_->config()) + " naming '" + name +
         "' written by '" + (writer.empty() ? std::string("an undiscovered writer") : writer) +
         "' (on a secured bus a participant may send only in its own name)");
    return false;
}

template <class Sample>
void LiveCorrelator::drain(ipc::dds::Reader<Sample>& reader, std::int64_t nowNs)
{
    Sample s;
    eprosima::fastdds::dds::SampleInfo info;
    while (reader.take(s, &info)) {
        ++stats_.received;
        auto message = adapters::fromDds(s);
        if (!message) {
            ++stats_.rejected;
            warn("correlator: refused: " + message.error().message());
            continue;
        }
        if (!sentByItsOwner(ipc::dds::sender(s), ipc::dds::TopicOf<Sample>::id, info)) {
            continue;
        }
        std::string sender = senderOf(s);
        if (!admit(sender, s.sequence_number(), info)) {
            continue;
        }
        reorder_.emplace(std::make_tuple(correlator::orderKey(*message), std::move(sender), s.sequence_number()),
                         Pending{std::move(*message), nowNs});
    }
}

void LiveCorrelator::onSnapshot(const correlator::Snapshot& s)
{
    latest_ = s;
    if (snapshotsLog_.is_open()) {
        snapshotsLog_ << adapters::toJsonLine(s) << '\n';
    }
    if (out_.valid()) {
        adapters::toDds(s, options_.source, stats_.published + 1, stats_.applied,
                        stats_.rejected + stats_.flooded + stats_.refused, sample_);
        if (out_.write(sample_)) {
            ++stats_.published;
        }
    }
}

void LiveCorrelator::apply(std::span<const correlator::Message> batch)
{
    if (batch.empty()) {
        return;
    }
    if (inputsLog_.is_open()) {
        for (const correlator::Message& m : batch) {
            inputsLog_ << adapters::toJsonLine(m) << '\n';
        }
    }
    const std::size_t skippedBefore = feed_.skippedSnapshots();
    stats_.applied += feed_.add(
        batch, [this](const correlator::Snapshot& s) { onSnapshot(s); },
        [this](const correlator::Message& /*message*/, const Error& e) {
            ++stats_.refused;
            warn("correlator: the correlator refused an input: " + e.message());
        });
    stats_.resequenced = feed_.resequenced();
    if (feed_.skippedSnapshots() > skippedBefore) {
        warn("correlator: an input jumped ahead in mission time: " +
             std::to_string(feed_.skippedSnapshots() - skippedBefore) + " snapshots of the gap skipped (at most " +
             std::to_string(correlator::CorrelatorFeed::kMaxSnapshotsPerGap) + " are given out for one gap)");
    }
}

void LiveCorrelator::waitForInput(std::chrono::milliseconds timeout)
{
    observations_.wait(timeout);
}

void LiveCorrelator::poll(std::int64_t nowNs)
{
    drain(observations_, nowNs);
    drain(uav_, nowNs);
    drain(confirmations_, nowNs);
    drain(corrections_, nowNs);
    if (firstArrivalNs_ == 0 && !reorder_.empty()) {
        firstArrivalNs_ = nowNs;
    }
    if (firstArrivalNs_ == 0 || nowNs - firstArrivalNs_ < static_cast<std::int64_t>(options_.startupHoldMs * 1e6)) {
        return; // gathering the histories
    }
    const auto reorderNs = static_cast<std::int64_t>(options_.reorderMs * 1e6);
    // Release in the correlator's order while the first has waited long enough (a later-arriving earlier one holds
    // the rest); one batch for the feed.
    batch_.clear();
    while (!reorder_.empty() && nowNs - reorder_.begin()->second.arrivalNs >= reorderNs) {
        batch_.push_back(std::move(reorder_.begin()->second.message));
        reorder_.erase(reorder_.begin());
    }
    apply(batch_);
    inputsLog_.flush();
    snapshotsLog_.flush();
}

std::optional<correlator::Snapshot> LiveCorrelator::finish()
{
    poll(0); // take what arrived (nothing is old enough at time 0)
    batch_.clear();
    for (auto& [key, pending] : reorder_) {
        batch_.push_back(std::move(pending.message));
    }
    reorder_.clear();
    apply(batch_);
    auto last = feed_.finish([this](const correlator::Snapshot& s) { onSnapshot(s); });
    if (out_.valid()) {
        out_.waitForAcks(std::chrono::milliseconds(2000));
    }
    inputsLog_.flush();
    snapshotsLog_.flush();
    return last;
}

LiveCorrelatorStats LiveCorrelator::stats() const
{
    LiveCorrelatorStats s = stats_;
    s.waiting = reorder_.size();
    return s;
}

Result<std::unique_ptr<CorrelatorTask>, Error>
CorrelatorTask::create(ipc::dds::Bus& bus, const LiveCorrelatorOptions& options, const rt::TaskSpec& spec)
{
    auto live = LiveCorrelator::create(bus, options);
    if (!live) {
        return Unexpected(live.error());
    }
    std::unique_ptr<CorrelatorTask> t(new CorrelatorTask());
    t->live_ = std::move(*live);
    if (auto added = t->runner_.addTask(spec, &CorrelatorTask::body, t.get()); !added) {
        return Unexpected(added.error());
    }
    if (auto created = t->runner_.createAll(); !created) {
        return Unexpected(created.error());
    }
    return t;
}

CorrelatorTask::~CorrelatorTask()
{
    stop();
}

void CorrelatorTask::start() noexcept
{
    runner_.startAll();
}

// A throw here (Fast DDS, std::bad_alloc) reaches rt::ThreadRunner's guard: logged, the body restarted after a
// back-off (on the state the throw left: a half-applied batch may be lost), disabled after repeated failures. The
// service's frame path runs in another runner and goes on either way.
void CorrelatorTask::body(void* self, const std::atomic<bool>& stop)
{
    auto* t = static_cast<CorrelatorTask*>(self);
    while (!stop.load(std::memory_order_relaxed)) {
        t->live_->waitForInput(std::chrono::milliseconds(50));
        t->live_->poll(MonotonicClock::nowNs());
        for (const std::string& w : t->live_->takeWarnings()) {
            UGV_LOG(Ipc, Warn) << w;
        }
        const std::lock_guard<std::mutex> lock(t->statsMutex_);
        t->stats_ = t->live_->stats();
    }
}

void CorrelatorTask::stop()
{
    if (stopped_) {
        return;
    }
    stopped_ = true;
    runner_.stopAll();
    live_->finish();
    for (const std::string& w : live_->takeWarnings()) {
        UGV_LOG(Ipc, Warn) << w;
    }
    const std::lock_guard<std::mutex> lock(statsMutex_);
    stats_ = live_->stats();
}

LiveCorrelatorStats CorrelatorTask::stats() const
{
    const std::lock_guard<std::mutex> lock(statsMutex_);
    return stats_;
}

} // namespace ugv::service
