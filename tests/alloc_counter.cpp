// Replaces the global operator new of the test binaries with one that counts its calls
// while a window is open (tests/test_alloc.cpp). Its own file: seen inline from the
// kernel's code, the replacement confuses g++'s flow warnings.
#include <atomic>
#include <cstdlib>
#include <new>

#pragma GCC diagnostic ignored "-Wmismatched-new-delete"  // free() of malloc()'s blocks, by design

namespace alloc_counter {
std::atomic<bool> counting{false};
std::atomic<long> news{0};
}  // namespace alloc_counter

namespace {
void* counted_new(std::size_t n) {
    if (alloc_counter::counting.load(std::memory_order_relaxed)) alloc_counter::news.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t n) { return counted_new(n); }
void* operator new[](std::size_t n) { return counted_new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
