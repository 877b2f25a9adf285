// Linked into every test executable (test/CMakeLists.txt) and benchmark (test/bench/CMakeLists.txt): with
// UGV_UNDER_QEMU set (the aarch64 test preset and toolchain/cross.sh set it), OpenCV's thread pool is turned off before
// any test runs. Under qemu-user 7.2 the pool's workers spin forever (100 % CPU, the test never ends) unless
// cv::setNumThreads(0) comes first. Natively nothing changes.

#include <cstdlib>

#include <opencv2/core/utility.hpp>

namespace {

bool openCvThreadsOffUnderQemu()
{
    // read-only, during static initialisation, no threads
    const char* env = std::getenv("UGV_UNDER_QEMU");
    if (env == nullptr || *env == '\0' || *env == '0') {
        return false;
    }
    cv::setNumThreads(0);
    return true;
}

[[maybe_unused]] const bool kOpenCvThreadsOff = openCvThreadsOffUnderQemu();

} // namespace
