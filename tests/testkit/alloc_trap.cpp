#include "testkit/alloc_trap.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

extern "C" {
void* __real_malloc(std::size_t size);
void* __real_calloc(std::size_t count, std::size_t size);
void* __real_realloc(void* ptr, std::size_t size);
void __real_free(void* ptr);
void* __real_aligned_alloc(std::size_t alignment, std::size_t size);
int __real_posix_memalign(void** out, std::size_t alignment, std::size_t size);
void* __real_memalign(std::size_t alignment, std::size_t size);
}

namespace {
std::atomic<bool> g_armed{false};
std::atomic<std::size_t> g_count{0};

void note_allocation() {
  if (g_armed.load(std::memory_order_relaxed)) g_count.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

namespace hivecal::test {
std::size_t armed_allocation_count() {
  return g_count.load();
}
void arm_allocation_trap() {
  g_count.store(0);
  g_armed.store(true);
}
std::size_t disarm_allocation_trap() {
  g_armed.store(false);
  return g_count.load();
}
}  // namespace hivecal::test

extern "C" {
void* __wrap_malloc(std::size_t size) {
  note_allocation();
  return __real_malloc(size);
}
void* __wrap_calloc(std::size_t count, std::size_t size) {
  note_allocation();
  return __real_calloc(count, size);
}
void* __wrap_realloc(void* ptr, std::size_t size) {
  note_allocation();
  return __real_realloc(ptr, size);
}
void __wrap_free(void* ptr) {
  __real_free(ptr);
}
void* __wrap_aligned_alloc(std::size_t alignment, std::size_t size) {
  note_allocation();
  return __real_aligned_alloc(alignment, size);
}
int __wrap_posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  note_allocation();
  return __real_posix_memalign(out, alignment, size);
}
void* __wrap_memalign(std::size_t alignment, std::size_t size) {
  note_allocation();
  return __real_memalign(alignment, size);
}
}

// Replaceable global allocation functions: counted, then served by malloc.
void* operator new(std::size_t size) {
  note_allocation();
  if (void* p = __real_malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  note_allocation();
  return __real_malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void operator delete(void* p) noexcept {
  __real_free(p);
}
void operator delete[](void* p) noexcept {
  __real_free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  __real_free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  __real_free(p);
}
