#include "ugv/vision/stage_times.hpp"

namespace ugv::vision {

const char* stageName(VisionStage stage) noexcept
{
    switch (stage) {
    case VisionStage::MatchOther:
        return "match_other";
    case VisionStage::Census:
        return "census";
    case VisionStage::Cost:
        return "cost";
    case VisionStage::Aggregate:
        return "aggregate";
    case VisionStage::LeftRight:
        return "left_right";
    case VisionStage::Speckle:
        return "speckle";
    case VisionStage::Ground:
        return "ground";
    case VisionStage::Warp:
        return "warp";
    case VisionStage::Mismatch:
        return "mismatch";
    case VisionStage::Verify:
        return "verify";
    case VisionStage::Sectors:
        return "sectors";
    }
    return "?";
}

} // namespace ugv::vision
