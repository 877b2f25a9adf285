// Planted: the service must not include the tool.
#include "ugv/tool/args.hpp"
