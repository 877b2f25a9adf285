#include "ugv/tool/bus_writers.hpp"

#include <algorithm>
#include <cstdio>

namespace ugv::tool::bus {

namespace msg = ipc::dds::msg;

namespace {

constexpr auto kSlice = std::chrono::milliseconds(100);

} // namespace

bool sleepUntil(Clock::time_point until)
{
    while (!gStop.load()) {
        const auto now = Clock::now();
        if (now >= until) {
            return true;
        }
        std::this_thread::sleep_for(std::min<Clock::duration>(kSlice, until - now));
    }
    return false;
}

Result<InputWriters, Error> InputWriters::create(ipc::dds::Bus& bus)
{
    InputWriters w;
    auto o = bus.writer<msg::OoiObservation>();
    auto u = bus.writer<msg::UavObservation>();
    auto c = bus.writer<msg::ConfirmationState>();
    auto p = bus.writer<msg::PoseCorrection>();
    for (const Error* e :
         {o ? nullptr : &o.error(), u ? nullptr : &u.error(), c ? nullptr : &c.error(), p ? nullptr : &p.error()}) {
        if (e != nullptr) {
            return Unexpected(*e);
        }
    }
    w.observations = *o;
    w.uav = *u;
    w.confirmations = *c;
    w.corrections = *p;
    return w;
}

int InputWriters::readers() const
{
    int r = 0;
    r = std::max(r, sent[0] > 0 ? observations.matched() : 0);
    r = std::max(r, sent[1] > 0 ? uav.matched() : 0);
    r = std::max(r, sent[2] > 0 ? confirmations.matched() : 0);
    r = std::max(r, sent[3] > 0 ? corrections.matched() : 0);
    return r;
}

bool InputWriters::waitForAcks()
{
    const auto until = Clock::now() + kAckTimeout;
    const auto left = [&] {
        return std::max(std::chrono::milliseconds(0),
                        std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()));
    };
    bool ok = true;
    ok = (sent[0] == 0 || observations.waitForAcks(left())) && ok;
    ok = (sent[1] == 0 || uav.waitForAcks(left())) && ok;
    ok = (sent[2] == 0 || confirmations.waitForAcks(left())) && ok;
    ok = (sent[3] == 0 || corrections.waitForAcks(left())) && ok;
    return ok;
}

void InputWriters::waitForReaders(const std::array<bool, 4>& used, const ReaderWait& wait,
                                  const ipc::dds::BusConfig& config, const std::string& command) const
{
    const auto until =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(wait.timeoutS));
    using ipc::dds::TopicId;
    if (used[0]) {
        bus::waitForReaders(observations, wait, until, topicName(TopicId::Observation, config), command);
    }
    if (used[1]) {
        bus::waitForReaders(uav, wait, until, topicName(TopicId::Uav, config), command);
    }
    if (used[2]) {
        bus::waitForReaders(confirmations, wait, until, topicName(TopicId::Confirmation, config), command);
    }
    if (used[3]) {
        bus::waitForReaders(corrections, wait, until, topicName(TopicId::PoseCorrection, config), command);
    }
}

int finish(InputWriters& w, const std::string& command, const std::string& what, double lingerS,
           const ipc::dds::BusConfig& config)
{
    const int matched = w.readers(); // before the wait: a reader that got everything may leave meanwhile
    const bool acked = w.waitForAcks();
    const int readers = std::max(matched, w.readers());
    std::printf("sent %llu message(s) (%llu observation(s), %llu UAV fix(es), %llu confirmation(s), %llu pose "
                "correction(s)) %s on %s, %s by %d reader(s)\n",
                static_cast<unsigned long long>(w.total()), static_cast<unsigned long long>(w.sent[0]),
                static_cast<unsigned long long>(w.sent[1]), static_cast<unsigned long long>(w.sent[2]),
                static_cast<unsigned long long>(w.sent[3]), what.c_str(), describe(config).c_str(),
                acked ? "acknowledged" : "NOT all acknowledged", readers);
    (void)std::fflush(stdout);
    if (!acked) {
        return reportError(
            command,
            Error{"ugvsense " + command,
                  "the readers did not acknowledge every message within " + std::to_string(kAckTimeout.count()) + " s",
                  "check the network between the hosts (loss, firewall) and that the readers keep up"});
    }
    if (lingerS > 0.0) {
        std::printf("lingering %g s (Ctrl-C to end)\n", lingerS);
        (void)std::fflush(stdout);
        sleepUntil(Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(lingerS)));
    }
    return 0;
}

} // namespace ugv::tool::bus
