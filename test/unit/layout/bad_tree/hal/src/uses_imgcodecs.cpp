// Fixture for the lint-deps self-test: service modules must not use imgcodecs. Not compiled.
#include <opencv2/imgcodecs.hpp>
