// Deliberately uses the heap. Never part of a firmware image: the tests prove that the no-heap
// check sees it (as an object file) and that it cannot link (port/baremetal has no _sbrk).
#include <cstdlib>
#include <new>

int main() {
  void* block = std::malloc(16);
  int* value = new (std::nothrow) int(3);
  const int status = block != nullptr && value != nullptr ? 0 : 1;
  delete value;
  std::free(block);
  return status;
}
