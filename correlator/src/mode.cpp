#include "ugv/correlator/mode.hpp"

namespace ugv::correlator {

std::optional<Mode> parseMode(std::string_view name) noexcept
{
    if (name == "original") {
        return Mode::Original;
    }
    if (name == "pose-corrected" || name == "improved") {
        return Mode::PoseCorrected;
    }
    return std::nullopt;
}

const char* modeName(Mode mode) noexcept
{
    return mode == Mode::Original ? "original" : "pose-corrected";
}

} // namespace ugv::correlator
