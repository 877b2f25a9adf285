// Without libFuzzer (GCC builds: the release and asan presets) each fuzz target is linked with this driver.
//
//   fuzz-<target> DIR|FILE...                                    every input once (ctest: fuzz-replay.<target>)
//   fuzz-<target> --mutate SECONDS [--seed N] [--crash FILE] DIR...   mutation run (ctest: fuzz-mutate.<target>)
//
// The mutation run is the short one of the test command: for SECONDS it takes a random input of the kept corpus,
// applies 1 to 4 random edits (a bit flipped, a byte set to a random or a boundary value, bytes inserted, erased or
// repeated, a number written in, a splice with another input) and runs it through the target; under the asan preset
// every run is checked by ASan and UBSan. It is blind (no coverage feedback, unlike libFuzzer's long runs with
// toolchain/fuzz.sh), but it reaches the inputs a few edits away from every kept one on every test run. The edits
// follow from the seed alone. On a crash (a sanitizer's report, an abort, a fatal signal) or a hang (one run longer
// than 10 s) the input that caused it is written to FILE (default fuzz-crash-<pid>) and named on stderr: replay it
// with `fuzz-<target> FILE`.
#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

#if defined(__has_include)
#if __has_include(<sanitizer/common_interface_defs.h>) && defined(__SANITIZE_ADDRESS__)
#include <sanitizer/common_interface_defs.h>
#define UGV_FUZZ_DEATH_CALLBACK 1
#endif
#endif

namespace {

using Bytes = std::vector<std::uint8_t>;

/// An edited input grows no larger (the targets' own limits are lower).
constexpr std::size_t kMaxInputBytes = std::size_t{1} << 20;
constexpr int kMaxEdits = 4;
constexpr std::size_t kMaxInsert = 16;
constexpr unsigned kRunTimeoutS = 10; ///< a run longer than this is a hang (libFuzzer's -timeout in toolchain/fuzz.sh)

// The input running now and where to write it if the run dies (read by the signal handler: volatile, so that no
// store is moved across the target's run).
const std::uint8_t* volatile gCurrent = nullptr;
volatile std::size_t gCurrentSize = 0;
std::array<char, 512> gCrashPath{};

/// Async-signal-safe: writes the running input to gCrashPath and says so.
void dumpCurrent()
{
    const std::uint8_t* const current = gCurrent;
    const std::size_t size = gCurrentSize;
    if (current == nullptr) {
        return;
    }
    const int fd = ::open(gCrashPath.data(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
        std::size_t done = 0;
        while (done < size) {
            const ssize_t n = ::write(fd, current + done, size - done);
            if (n <= 0) {
                break;
            }
            done += static_cast<std::size_t>(n);
        }
        ::close(fd);
    }
    constexpr char kSaid[] = "fuzz mutate: the input that crashed is in ";
    (void)!::write(STDERR_FILENO, kSaid, sizeof(kSaid) - 1);
    (void)!::write(STDERR_FILENO, gCrashPath.data(), std::strlen(gCrashPath.data()));
    (void)!::write(STDERR_FILENO, "\n", 1);
    gCurrent = nullptr;
}

extern "C" void onFatalSignal(int sig)
{
    if (sig == SIGALRM) {
        constexpr char kHang[] = "fuzz mutate: one run took longer than the timeout (a hang)\n";
        (void)!::write(STDERR_FILENO, kHang, sizeof(kHang) - 1);
    }
    dumpCurrent();
    std::signal(sig, SIG_DFL);
    (void)std::raise(sig);
}

void installCrashDump()
{
    for (const int sig : {SIGSEGV, SIGABRT, SIGBUS, SIGFPE, SIGILL, SIGALRM}) {
        (void)std::signal(sig, onFatalSignal);
    }
#ifdef UGV_FUZZ_DEATH_CALLBACK
    __sanitizer_set_death_callback(dumpCurrent);
#endif
}

bool readFile(const std::filesystem::path& file, Bytes& bytes)
{
    std::ifstream in(file, std::ios::binary);
    if (!in) {
        std::fprintf(stderr, "fuzz replay: error: cannot read %s\n", file.c_str());
        return false;
    }
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return true;
}

/// The files of the given folders (sorted) and the given files.
bool collect(const std::vector<std::string>& paths, std::vector<std::filesystem::path>& files)
{
    for (const std::string& p : paths) {
        const std::filesystem::path path(p);
        std::error_code ec;
        if (std::filesystem::is_directory(path, ec)) {
            std::vector<std::filesystem::path> inFolder;
            for (const auto& entry : std::filesystem::directory_iterator(path)) {
                if (entry.is_regular_file()) {
                    inFolder.push_back(entry.path());
                }
            }
            std::sort(inFolder.begin(), inFolder.end());
            files.insert(files.end(), inFolder.begin(), inFolder.end());
        } else {
            files.push_back(path);
        }
    }
    if (files.empty()) {
        std::fprintf(stderr, "fuzz replay: error: no input in the given folders: keep a corpus in test/fuzz/corpus\n");
        return false;
    }
    return true;
}

void run(const Bytes& input)
{
    gCurrent = input.data();
    gCurrentSize = input.size();
    ::alarm(kRunTimeoutS);
    (void)LLVMFuzzerTestOneInput(input.data(), input.size());
    ::alarm(0);
    gCurrent = nullptr;
}

/// One random edit of `b`; `corpus` gives splices.
void edit(Bytes& b, const std::vector<Bytes>& corpus, std::mt19937_64& rng)
{
    const auto pick = [&rng](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
    // 1 to kMaxInsert bytes of a non-empty `b`.
    const auto pickRange = [&b, &pick] {
        const std::size_t at = pick(b.size());
        const std::size_t n = 1 + pick(std::min(b.size() - at, kMaxInsert));
        return std::pair{b.begin() + static_cast<std::ptrdiff_t>(at), b.begin() + static_cast<std::ptrdiff_t>(at + n)};
    };
    static constexpr std::array<std::uint8_t, 8> kBoundary{0x00, 0x01, 0x7f, 0x80, 0xff, '-', '9', '\n'};
    static constexpr std::array<const char*, 8> kNumbers{"0",   "-1",  "1e308",      "-1e308",
                                                         "nan", "inf", "4294967296", "99999999999999999999"};
    switch (pick(7)) {
    case 0: // flip a bit
        if (!b.empty()) {
            b[pick(b.size())] ^= static_cast<std::uint8_t>(1U << pick(8));
        }
        break;
    case 1: // a byte to a random or a boundary value
        if (!b.empty()) {
            b[pick(b.size())] = pick(2) == 0 ? static_cast<std::uint8_t>(pick(256)) : kBoundary[pick(kBoundary.size())];
        }
        break;
    case 2: { // insert random bytes
        const std::size_t at = pick(b.size() + 1);
        Bytes bytes(1 + pick(kMaxInsert));
        for (auto& x : bytes) {
            x = static_cast<std::uint8_t>(pick(256));
        }
        b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), bytes.begin(), bytes.end());
        break;
    }
    case 3: // erase a range
        if (!b.empty()) {
            const auto [first, last] = pickRange();
            b.erase(first, last);
        }
        break;
    case 4: // repeat a range
        if (!b.empty()) {
            const auto [first, last] = pickRange();
            const Bytes range(first, last);
            b.insert(first, range.begin(), range.end());
        }
        break;
    case 5: { // write a number in
        const char* number = kNumbers[pick(kNumbers.size())];
        const std::size_t at = pick(b.size() + 1);
        b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), number, number + std::strlen(number));
        break;
    }
    default: { // splice: this input's head, another's tail
        const Bytes& other = corpus[pick(corpus.size())];
        const std::size_t head = pick(b.size() + 1);
        const std::size_t from = pick(other.size() + 1);
        b.resize(head);
        b.insert(b.end(), other.begin() + static_cast<std::ptrdiff_t>(from), other.end());
        break;
    }
    }
    if (b.size() > kMaxInputBytes) {
        b.resize(kMaxInputBytes);
    }
}

int mutate(const std::vector<std::filesystem::path>& files, double seconds, std::uint64_t seed)
{
    std::vector<Bytes> corpus(files.size());
    for (std::size_t i = 0; i < files.size(); ++i) {
        if (!readFile(files[i], corpus[i])) {
            return 1;
        }
    }
    installCrashDump();
    std::mt19937_64 rng(seed);
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    std::uint64_t runs = 0;
    Bytes input;
    while (std::chrono::steady_clock::now() < until) {
        input = corpus[std::uniform_int_distribution<std::size_t>(0, corpus.size() - 1)(rng)];
        const int edits = std::uniform_int_distribution<int>(1, kMaxEdits)(rng);
        for (int e = 0; e < edits; ++e) {
            edit(input, corpus, rng);
        }
        run(input);
        ++runs;
    }
    std::printf("fuzz mutate: %llu mutated input(s) of %zu kept ran without a crash (seed %llu, %.0f s)\n",
                static_cast<unsigned long long>(runs), corpus.size(), static_cast<unsigned long long>(seed), seconds);
    return 0;
}

int usage(const char* self)
{
    std::fprintf(stderr,
                 "usage: %s DIR|FILE...                  runs each input through the fuzz target once\n"
                 "       %s --mutate SECONDS [--seed N] [--crash FILE] DIR|FILE...\n"
                 "                                       runs random edits of the inputs for SECONDS\n",
                 self, self);
    return 2;
}

} // namespace

int main(int argc, char** argv)
{
    double mutateSeconds = -1.0;
    std::uint64_t seed = 1;
    std::string crash = "fuzz-crash-" + std::to_string(::getpid());
    std::vector<std::string> paths;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--crash" && i + 1 < argc) {
            crash = argv[++i];
        } else if ((arg == "--mutate" || arg == "--seed") && i + 1 < argc) {
            const std::string value = argv[++i];
            char* end = nullptr;
            if (arg == "--mutate") {
                mutateSeconds = std::strtod(value.c_str(), &end);
            } else {
                seed = std::strtoull(value.c_str(), &end, 10);
            }
            if (value.empty() || *end != '\0' || (arg == "--mutate" && !(mutateSeconds >= 0.0))) {
                std::fprintf(stderr, "fuzz replay: error: %s wants a number (seconds >= 0), not '%s'\n", arg.c_str(),
                             value.c_str());
                return 2;
            }
        } else if (!arg.empty() && arg[0] == '-') {
            return usage(argv[0]);
        } else {
            paths.push_back(arg);
        }
    }
    if (paths.empty()) {
        return usage(argv[0]);
    }
    if (crash.size() >= gCrashPath.size()) {
        std::fprintf(stderr, "fuzz replay: error: --crash path longer than %zu characters: give a shorter one\n",
                     gCrashPath.size() - 1);
        return 2;
    }
    std::vector<std::filesystem::path> files;
    if (!collect(paths, files)) {
        return 1;
    }
    if (mutateSeconds >= 0.0) {
        std::memcpy(gCrashPath.data(), crash.c_str(), crash.size() + 1);
        return mutate(files, mutateSeconds, seed);
    }
    for (const auto& file : files) {
        Bytes bytes;
        if (!readFile(file, bytes)) {
            return 1;
        }
        run(bytes);
    }
    std::printf("fuzz replay: %zu input(s) ran without a crash\n", files.size());
    return 0;
}
