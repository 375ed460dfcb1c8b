// store_kernel.hpp at -O2 (tests/compiler/CMakeLists.txt), the level at which g++ 12.2 lost
// the mirror's stores in the demo binary.
#define CTXFUSE_STORE_NS o2
#include "store_variant.inc"
