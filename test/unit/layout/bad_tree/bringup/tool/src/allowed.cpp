// Allowed (not a violation): the tool may include everything, image files too.
#include <opencv2/imgcodecs.hpp>
#include "ugv/service/service.hpp"
#include "ugv/sim/scene.hpp"
