// The run layer tests' scene: a block of sand (a μ(I) material, 8 points per cell) in a box of
// 12 x 6 x 10 cells of 0.01 m, under gravity.
#pragma once
#include <string>

#include "scene/MpmScene.hpp"

namespace mpmsdem {
namespace run {
namespace testing_scenes {

// The scene with `runJson` as its "run" object.
inline mpm::MpmScene sandInABox(const std::string& runJson) {
  return mpm::parseScene(R"({
    "grid": {"dx": 0.01, "cells": [12, 6, 10], "origin": [0, 0, 0]},
    "gravity": {"g": 9.81},
    "material": {"density": 1600, "young_modulus": 1e6, "poisson_ratio": 0.3, "mu_s": 0.24, "mu_2": 0.65,
                 "grain_diameter": 0.001, "critical_density": 1500},
    "particles": [{"lo": [0.02, 0.02, 0.02], "hi": [0.06, 0.04, 0.06], "ppc": 8}],
    "run": )" + runJson + "}");
}

}  // namespace testing_scenes
}  // namespace run
}  // namespace mpmsdem
