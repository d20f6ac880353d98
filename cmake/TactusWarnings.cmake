# Warnings on for our own targets (not for third-party headers, which come in as SYSTEM).
function(tactus_target_defaults target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                           -Wold-style-cast -Wcast-align -Woverloaded-virtual
                                           -Wconversion -Wno-sign-conversion
                                           # a portable build (no AVX) notes that returning the stress kernels'
                                           # 32-byte lane vectors changes the calling convention: they are all
                                           # inlined within one file, so there is no ABI to change
                                           -Wno-psabi)
  if(TACTUS_NATIVE)
    # AVX-512 off: GCC 12 warns falsely inside its AVX-512 intrinsics, and AVX2+FMA measured as fast.
    target_compile_options(${target} PRIVATE -march=native -mno-avx512f)
  endif()
  if(TACTUS_EXACT_FP)
    target_compile_options(${target} PRIVATE -ffp-contract=off)
  endif()
  if(TACTUS_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(TACTUS_SANITIZE)
    # -fno-sanitize-recover: undefined behaviour stops the program, so a test that meets it fails.
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined -fno-sanitize-recover=undefined)
  endif()
endfunction()
