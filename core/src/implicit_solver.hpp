// The implicit solver's state (owned by Simulation): the sweeps of the cloth itself and, for a cloth of the fabric
// model that can be rebuilt coarser (a grid, an outline), a hierarchy of the same fabric at coarser spacings that gives each step a coarse-to-fine initial guess
// (docs/implicit.md, "Multilevel initial guess").
#pragma once

#include <cstdint>
#include <vector>

#include "drape/cloth.hpp"
#include "drape/level_transfer.hpp"
#include "vbd.hpp"

namespace drape {

/// CoarseLevel::held values.
enum : std::uint8_t { node_free = 0, node_fixed = 1, node_touching = 2 };

/// One coarser copy of the same fabric (Cloth::coarsen), with its own state for the current step.
struct CoarseLevel {
    Cloth cloth;
    vbd::Solver solver;
    LevelTransfer from_fine; ///< the cloth's particles onto this level's nodes
    LevelTransfer to_finer;  ///< this level onto the next finer one (the cloth itself for the first)
    std::vector<float> x0, y0, z0;    ///< x^n, sampled from the cloth's state
    std::vector<float> vx, vy, vz;    ///< v^n, sampled (then the collide pass's scratch)
    std::vector<float> gx, gy, gz;    ///< the cloth's own initial guess, sampled (fixed nodes: x^n)
    std::vector<float> x, y, z;       ///< the iterate
    std::vector<float> inv_mass;      ///< this step's: 0 where the nearest particle of the cloth is fixed
    std::vector<float> free_inv_mass; ///< the level's own masses
    std::vector<std::uint32_t> nearest; ///< per node: the nearest particle of the cloth (pins, grabs)
    /// Per node of the next finer level (the cloth's particles for the first): this level's node nearest to it, so a
    /// fixed particle holds the node that stands for it on every level (held), not only a node whose nearest
    /// particle it happens to be.
    std::vector<std::uint32_t> up;
    /// This step's: node_fixed where the node stands for a fixed particle of the cloth, node_touching where its
    /// interpolation reaches a particle that touches or may touch a collider (multilevel_guess), else node_free.
    std::vector<std::uint8_t> held;
    std::vector<float> rx, ry, rz;    ///< the cloth's force residual at x^n restricted onto this level (N)
    std::vector<float> tx, ty, tz;    ///< scratch: this level's own residual at x^n
    std::vector<float> rest0, rest;   ///< per Cloth::edges entry: the natural rest length and this step's
    double sweep_factor = 2.0;        ///< its sweeps per step over the cloth's (implicit_step.cpp)
    bool slack = false;               ///< the solver's springs hold `rest` (FAS), not `rest0`
};

struct ImplicitSolver {
    vbd::Solver fine;
    std::vector<CoarseLevel> coarse; ///< finer first
    std::vector<float> corr_x, corr_y, corr_z; ///< the finest coarse level's correction, sampled onto the cloth
    std::vector<float> res_x, res_y, res_z;    ///< the cloth's force residual at x^n (N); then gradient scratch
    std::vector<double> block_dot;             ///< per block of particles: a partial dot product
    std::vector<std::uint8_t> touching; ///< per particle, this step's: it touches or may touch a collider
    /// Per particle: its piece of cloth (joined by springs) as a union-find root, and per root whether the piece holds
    /// a fixed particle (the first step's guess, implicit_step.cpp).
    std::vector<std::uint32_t> piece;
    std::vector<std::uint8_t> piece_held;
    std::uint32_t slow_steps = 0; ///< steps in a row with an rms speed below the bound to start FAS at rest
    std::uint32_t guess_slow_steps = 0; ///< steps in a row with an rms speed below guess_rest_speed (implicit_step.cpp)
    double rms_speed = 0.0;             ///< this step's at x^n (m/s): the guess's rest test and FAS at rest's
    bool at_rest = false;         ///< ImplicitParams::fas_at_rest engaged
    std::uint32_t rest_steps = 0; ///< steps since FAS at rest started
    float rest_scale = 1.0f;      ///< the bound to start FAS at rest is fas_rest_on x this (halved when FAS fed motion)
};

} // namespace drape
