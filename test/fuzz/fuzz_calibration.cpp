// Fuzz target: a calibration file's text (full or rectified form) as `detect`, `rectify`, `check-config` and the
// service read it.
#include <cstddef>
#include <cstdint>
#include <string>

#include "ugv/adapters/calibration_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    (void)ugv::adapters::parseCalibration(text, "fuzz.yaml");
    return 0;
}
