#!/usr/bin/env bash
# Proves a firmware ELF (or object file) contains no heap machinery: fails if any allocator,
# sbrk, operator new/delete or exception-allocation symbol is defined or referenced in it.
# Together with the missing _sbrk in port/baremetal (any malloc fails to link) this shows the
# library and firmware run without a heap.
#   scripts/check-no-heap.sh <file.elf|file.o>...      (NM=arm-none-eabi-nm by default)
set -euo pipefail

if [ $# -lt 1 ]; then
  echo "usage: $0 <elf-or-object>..." >&2
  exit 64
fi
nm_tool=${NM:-arm-none-eabi-nm}

# Mangled names: _Znwj/_Znaj = operator new/new[] (size_t = unsigned int on ARM, also
# _Znwm/_Znam elsewhere), _ZdlPv/_ZdaPv = operator delete/delete[] (all overloads start so).
# Placement new/delete (_ZnwjPv, _ZdlPvS_: no allocation, out of line at -O0) are allowed.
forbidden='^(malloc|_malloc_r|calloc|_calloc_r|realloc|_realloc_r|reallocf|_reallocf_r|free|_free_r|memalign|_memalign_r|aligned_alloc|posix_memalign|valloc|pvalloc|_malloc_trim_r|mallinfo|_sbrk|_sbrk_r|sbrk|__malloc_lock|_Zn[wa][jm].*|_Zd[la]Pv.*|__cxa_allocate_exception|__cxa_free_exception|__cxa_throw|__cxa_allocate_dependent_exception|_Unwind_RaiseException|__gxx_personality_v0)$'

placement='^(_Zn[wa][jm]Pv|_Zd[la]PvS_)$'

status=0
for file in "$@"; do
  found=$("$nm_tool" "$file" | awk '{print $NF}' | grep -E "$forbidden" | grep -Ev "$placement" | sort -u || true)
  if [ -n "$found" ]; then
    echo "check-no-heap: FAIL $file contains heap symbols:" >&2
    while read -r sym; do
      printf '  %s  (%s)\n' "$sym" "$(c++filt "$sym" 2>/dev/null || echo "$sym")" >&2
    done <<<"$found"
    status=1
  else
    echo "check-no-heap: OK $file (no allocator, sbrk, operator new/delete or exception allocation)"
  fi
done
exit $status
