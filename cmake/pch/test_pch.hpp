// Precompiled once per build and reused by every livod test executable (LIVOD_PCH,
// cmake/LivodTargets.cmake): GoogleTest, Eigen and the standard headers most tests parse.
// Only third-party headers belong here: a project header would make every test rebuild when it
// changes. A test must still include what it uses: builds without LIVOD_PCH (other compilers,
// -DLIVOD_PCH=OFF) do not see these.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>
