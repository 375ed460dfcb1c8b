// store_kernel.hpp at -O0 (tests/compiler/CMakeLists.txt): the reference the -O2 copy must
// match bit for bit, since both evaluate the same operations in the same order.
#define CTXFUSE_STORE_NS o0
#include "store_variant.inc"
