// The sanitizer build's canary (CI's ASan + UBSan pass): each mode commits one error the
// sanitizers must stop. Registered only with -DTACTUS_SANITIZE=ON, as tests that must fail
// (WILL_FAIL): if a sanitizer stops catching, its canary exits 0 and the inverted test fails.
//   tactus-sanitizer-canary signed-overflow | heap-overflow | use-after-free
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  const int n = argc;  // not a constant the compiler could fold
  if (std::strcmp(argv[1], "signed-overflow") == 0) {
    const int big = INT_MAX - 1 + n / 2;  // INT_MAX with two arguments
    const int wrapped = big + n;          // undefined behaviour: UBSan aborts here
    std::printf("no sanitizer stopped the overflow: %d\n", wrapped);
    return 0;
  }
  if (std::strcmp(argv[1], "heap-overflow") == 0) {
    std::vector<int> v(static_cast<std::size_t>(n));
    const int* p = v.data();
    std::printf("no sanitizer stopped the read past the end: %d\n", p[n + 2]);  // ASan aborts here
    return 0;
  }
  if (std::strcmp(argv[1], "use-after-free") == 0) {
    int* p = static_cast<int*>(std::malloc(sizeof(int) * static_cast<std::size_t>(n)));
    p[0] = n;
    std::free(p);
    std::printf("no sanitizer stopped the use after free: %d\n", p[0]);  // ASan aborts here
    return 0;
  }
  return 2;
}
