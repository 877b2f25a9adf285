// Fixture for the lint-deps self-test: vision/ must not include hal/. Not compiled.
#include "ugv/hal/camera_source.hpp"
