// Fixture for the lint-deps self-test: platform/ must not include any other module. Not compiled.
#include <ugv/vision/rectifier.hpp>
