// The translation unit that builds the tests' shared precompiled header
// (tests/CMakeLists.txt, meshlight_test_pch); it defines nothing.
