// Planted: the simulator must not include the vision code it judges.
#include "ugv/vision/rectifier.hpp"
