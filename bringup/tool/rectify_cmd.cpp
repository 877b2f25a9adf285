#include "commands.hpp"
namespace ugv::tool {
int runRectify(int /*argc*/, char** /*argv*/)
{
    return 1;
} // replaced by the real command
} // namespace ugv::tool
