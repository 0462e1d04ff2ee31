# Strict warnings for every target of this project (not for third-party code).
function(hivecal_strict_warnings target)
  target_compile_options(${target} PRIVATE
    -Wall -Wextra -Wpedantic -Werror -Wconversion -Wsign-conversion -Wshadow
    -Wdouble-promotion -Wcast-align -Wnull-dereference)
endfunction()
