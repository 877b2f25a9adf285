// Planted findings for lint-tidy-selftest (not compiled, not part of the product): each line marked "finding" breaks
// one check that .clang-tidy turns on; the line after the NOLINT must not be reported.
#include <cstdlib>
#include <string>
#include <utility>

using namespace std; // finding: google-build-using-namespace

int countDown(int n) // finding: misc-no-recursion
{
    return n <= 0 ? 0 : countDown(n - 1);
}

void planted()
{
    ::setenv("UGV_PLANTED", "1", 1); // finding: concurrency-mt-unsafe
    int Bad_name = 0;                // finding: readability-identifier-naming
    (void)Bad_name;
    void* p = std::malloc(4); // finding: cppcoreguidelines-no-malloc
    // NOLINTNEXTLINE(cppcoreguidelines-no-malloc): allowed, with its reason
    void* q = std::malloc(8);
    std::free(p); // finding: cppcoreguidelines-no-malloc
    std::free(q); // NOLINT(cppcoreguidelines-no-malloc): allowed, with its reason
    string a = "moved";
    string b = std::move(a);
    (void)a.size(); // finding: bugprone-use-after-move
    (void)b;
}
