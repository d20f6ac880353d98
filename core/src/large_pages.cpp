// Large allocations on transparent huge pages, for every tactus executable (linked through
// tactus_cli). A 136 M-voxel scan allocates and zeroes a dozen arrays of 136-544 MB; on 4 KB pages
// each page's first touch is a fault, and on the VMs we measured those faults were a third of the
// segment stage (bench/ct_bench.sh: labels 36.7 s -> 21.5 s with huge pages). Debian's kernels
// give huge pages only to memory advised with MADV_HUGEPAGE ("madvise" mode), and glibc advises
// nothing unless told by an environment tunable, so allocations of 32 MB and more are made 2 MB
// aligned and advised here. Smaller ones go to malloc as before; everything is released by free.
// Not under AddressSanitizer, which must see its own operator new.
#if !defined(__SANITIZE_ADDRESS__)
#include <sys/mman.h>

#include <cstdlib>
#include <new>

namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;
constexpr std::size_t kLarge = std::size_t{32} << 20;

void* allocate(std::size_t size) {
  if (size >= kLarge) {
    const std::size_t rounded = (size + kHugePage - 1) / kHugePage * kHugePage;
    if (void* p = std::aligned_alloc(kHugePage, rounded)) {
      madvise(p, rounded, MADV_HUGEPAGE);  // a hint: ignored where huge pages are off
      return p;
    }
  } else if (void* p = std::malloc(size > 0 ? size : 1)) {
    return p;
  }
  throw std::bad_alloc();
}

}  // namespace

void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#endif
