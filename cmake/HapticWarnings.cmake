# Project-wide compile settings applied per target (no global flags).
add_library(haptic_compile_options INTERFACE)
add_library(haptic::compile_options ALIAS haptic_compile_options)
target_compile_options(haptic_compile_options INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor>)
if(HAPTIC_ENABLE_ASAN)
  # Not vptr: gRPC's libraries are built without RTTI, so UBSan cannot check the dynamic type of
  # the objects they make, and reports their shared_ptr control blocks as having "invalid vptr".
  target_compile_options(haptic_compile_options INTERFACE -fsanitize=address,undefined
                         -fno-sanitize=vptr -fno-omit-frame-pointer)
  target_link_options(haptic_compile_options INTERFACE -fsanitize=address,undefined -fno-sanitize=vptr)
endif()

# haptic_apply_options(<target>): private warnings and sanitizer flags for one of our targets.
function(haptic_apply_options target)
  target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:haptic::compile_options>)
endfunction()

# haptic_apply_c_options(<target>): the same for a C program of ours (the C API's example, test
# and benchmark): C99 without extensions, warnings as errors, and the sanitizers with the rest
# (a C program loading the instrumented libhaptic_c must bring their runtime first).
function(haptic_apply_c_options target)
  set_target_properties(${target} PROPERTIES C_STANDARD 99 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
  target_compile_options(${target} PRIVATE $<$<C_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Werror>)
  if(HAPTIC_ENABLE_ASAN)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()
