// The source of the precompiled-header target of tests/CMakeLists.txt: CMake builds the
// precompiled header (GoogleTest, Eigen, the library, the simulator, the test helpers)
// with this empty file, and the test executables reuse it.
