#pragma once

/// @file
/// Sending on the DDS bus from a command-line sender (`ugvsense bus-send`, and the test tool `bus-hostile`): the
/// four writers of the correlator's inputs, waits for readers and acknowledgements, writes that retry while a
/// keep-all history is full, and the summary line. Every wait ends on SIGINT/SIGTERM (gStop). Init-time
/// and tool code only (allocates, blocks).

#include <array>
#include <chrono>
#include <cstdint>
#include <iostream>
#include <string>
#include <thread>

#include "ugv/ipc/dds_bus.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/bus_options.hpp"

namespace ugv::tool::bus {

using Clock = std::chrono::steady_clock;

inline constexpr double kDefaultWaitReadersS = 20.0; ///< bus-send's --wait-timeout default
inline constexpr auto kAckTimeout = std::chrono::seconds(60);
inline constexpr auto kRefusedWriteTimeout = std::chrono::seconds(30); ///< a writer refusing every sample this long
// Adelaide, the MAGIC 2010 site: where the senders' vehicles drive and their objects stand.
inline constexpr double kSiteLat = -34.9285;
inline constexpr double kSiteLon = 138.6007;

/// Sleeps until `until` in short slices; false when a signal stopped it first.
bool sleepUntil(Clock::time_point until);

/// How many matched readers a sender waits for before it sends, and for how long at most.
struct ReaderWait {
    int readers = 1;
    double timeoutS = kDefaultWaitReadersS;
    /// The bus to join again while a reader is missing and a secured handshake has not ended after kHandshakeStall
    /// (rejoinIfStalled()); nullptr: just wait.
    ipc::dds::Bus* bus = nullptr;
};

/// Waits until `until` for wait.readers matched readers of `writer`, joining wait.bus again while a handshake is
/// stalled; a warning on stderr if fewer came.
template <class T>
void waitForReaders(const ipc::dds::Writer<T>& writer, const ReaderWait& wait, Clock::time_point until,
                    const std::string& topic, const std::string& command)
{
    if (wait.readers <= 0) {
        return;
    }
    bool rejoin = wait.bus != nullptr; // until joining again fails (said once)
    while (writer.matched() < wait.readers && Clock::now() < until && !gStop.load()) {
        if (rejoin && rejoinIfStalled(*wait.bus, command) == Rejoin::Failed) {
            rejoin = false;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (writer.matched() < wait.readers && !gStop.load()) {
        std::cerr << "ugvsense " << command << ": warning: " << writer.matched() << " of " << wait.readers
                  << " reader(s) of " << topic << " after " << wait.timeoutS
                  << " s; sending anyway (late reliable readers get the history while this process lives)\n";
    }
}

/// As above, for up to wait.timeoutS from now.
template <class T>
void waitForReaders(const ipc::dds::Writer<T>& writer, const ReaderWait& wait, const std::string& topic,
                    const std::string& command)
{
    waitForReaders(writer, wait,
                   Clock::now() +
                       std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(wait.timeoutS)),
                   topic, command);
}

/// Writes one sample, retrying while Fast DDS refuses it (a full keep-all history: a reader is slow to
/// acknowledge). False after kRefusedWriteTimeout or a signal.
template <class T>
bool writeOne(ipc::dds::Writer<T>& writer, const T& sample)
{
    const auto until = Clock::now() + kRefusedWriteTimeout;
    while (!writer.write(sample)) {
        if (gStop.load() || Clock::now() >= until) {
            return false;
        }
    }
    return true;
}

/// The four writers of the correlator's inputs and what each sent.
struct InputWriters {
    ipc::dds::Writer<ipc::dds::msg::OoiObservation> observations;
    ipc::dds::Writer<ipc::dds::msg::UavObservation> uav;
    ipc::dds::Writer<ipc::dds::msg::ConfirmationState> confirmations;
    ipc::dds::Writer<ipc::dds::msg::PoseCorrection> corrections;
    std::array<std::uint64_t, 4> sent{}; ///< per topic, in this order

    static Result<InputWriters, Error> create(ipc::dds::Bus& bus);
    [[nodiscard]] std::uint64_t total() const { return sent[0] + sent[1] + sent[2] + sent[3]; }
    /// The most readers any used writer has.
    [[nodiscard]] int readers() const;
    /// Waits for wait.readers readers of each topic marked in `used` (in the writers' order), all within
    /// wait.timeoutS: a reader that matches only after the samples were written gets them from the writer's history
    /// only while the sender lives.
    void waitForReaders(const std::array<bool, 4>& used, const ReaderWait& wait, const ipc::dds::BusConfig& config,
                        const std::string& command) const;
    /// Every used writer's samples acknowledged by all its matched reliable readers, within kAckTimeout in all.
    bool waitForAcks();
};

/// The end of a reliable sender: acknowledgements, the summary line ("sent N message(s) ... WHAT on BUS,
/// acknowledged by R reader(s)"), then `lingerS` more seconds. The exit code: 1 when not all was acknowledged.
int finish(InputWriters& w, const std::string& command, const std::string& what, double lingerS,
           const ipc::dds::BusConfig& config);

} // namespace ugv::tool::bus
