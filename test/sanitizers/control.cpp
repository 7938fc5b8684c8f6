// The sanitizer tests' negative control: one deliberate fault per run, compiled with the same
// flags as the libraries and gtest programs of the sanitizer build it belongs to
// (-DHAMERITT_SANITIZE=...). test/scripts/test_sanitizers_asan.sh and test_sanitizers_tsan.sh run
// it through the same judge as the gtest programs and require each fault to be reported and to
// fail the run, and "none" to pass.
//   sanitizer_control none|heap-buffer-overflow|use-after-free|signed-integer-overflow|leak|
//                     data-race
#include <climits>
#include <cstdio>
#include <cstring>
#include <thread>
#include <vector>

namespace {

// Opaque to the optimiser: the faults below must happen at -O1.
volatile int g_index = 8;
volatile int g_big = INT_MAX;
int* volatile g_lost = nullptr;
int g_shared = 0;  // written by two threads without a lock

}  // namespace

int main(int argc, char** argv) {
  const char* fault = argc > 1 ? argv[1] : "";
  if (std::strcmp(fault, "none") == 0) {
    std::vector<int> v(8, 1);
    std::thread t([&v] { v[0] = 2; });
    t.join();
    return v[0] == 2 ? 0 : 1;
  }
  if (std::strcmp(fault, "heap-buffer-overflow") == 0) {
    std::vector<int> v(8, 1);
    return v.data()[g_index];  // one past the end
  }
  if (std::strcmp(fault, "use-after-free") == 0) {
    int* p = new int[4]();
    delete[] p;
    return p[g_index % 4];
  }
  if (std::strcmp(fault, "signed-integer-overflow") == 0) {
    int x = g_big;
    x += argc;  // INT_MAX + 2
    return x == 0 ? 1 : 0;
  }
  if (std::strcmp(fault, "leak") == 0) {
    g_lost = new int[1000]();
    g_lost = nullptr;
    return 0;
  }
  if (std::strcmp(fault, "data-race") == 0) {
    std::thread t([] { ++g_shared; });
    ++g_shared;
    t.join();
    return g_shared == 2 ? 0 : 0;
  }
  std::fprintf(stderr,
               "usage: %s none|heap-buffer-overflow|use-after-free|"
               "signed-integer-overflow|leak|data-race\n",
               argv[0]);
  return 2;
}
