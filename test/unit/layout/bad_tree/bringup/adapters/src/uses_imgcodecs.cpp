// Planted: the adapters are linked by the service, which must not read image files.
#include <opencv2/imgcodecs.hpp>
