#include "run_command.hpp"

#include <cstdio>
#include <fstream>
#include <iterator>

#include <sys/wait.h>

namespace ugv::test {

CommandRun runCommand(const std::string& commandLine)
{
    const std::string command = commandLine + " 2>&1";
    CommandRun result;
    FILE* pipe = popen(command.c_str(), "r"); // test harness runs our own binary
    if (pipe == nullptr) {
        return result;
    }
    char buffer[512];
    while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) {
        result.output += buffer;
    }
    const int status = pclose(pipe);
    result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return result;
}

std::string readText(const std::filesystem::path& path)
{
    std::ifstream in(path);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeText(const std::filesystem::path& path, const std::string& text)
{
    std::ofstream(path) << text;
}

} // namespace ugv::test
