// The one source of ctxfuse_test_pch (tests/CMakeLists.txt): CMake builds the tests'
// precompiled header with this target's flags, and every test executable reuses it.
