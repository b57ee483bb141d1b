// The one source of the target that owns the tests' precompiled header (cmake/LivodTargets.cmake):
// CMake builds a precompiled header with its owner's flags, so the owner has the flags of the tests
// that reuse it. Nothing is defined here (GoogleTest's main links in).
