// Sewing (SimulationParams::sewing_speed, on by default): seams that start open are pulled shut at a set speed, and
// seams that start shorter than their rest length are let out to it the same way. Each seam's rest length starts at
// its length in the initial state (or a saved state's InitialState::seam_rest) and moves by speed x dt every step to
// its own rest length (Edge::rest):  l0_k <- max(rest_k, l0_k - speed dt)  (or min(rest_k, l0_k + speed dt)).
// The seam spring then pulls only by what the cloth lags behind the schedule, so the panels are drawn together
// smoothly instead of snapping shut in one substep. Every consumer of a seam's rest length reads the current one:
// seam_forces (seam_rest_), strain limiting (its copy, limit_rest_), the implicit solver (vbd::Solver::set_spring_rest)
// and the health figures (edge_rest_). Serial, while a seam is still closing (nothing after): O(seams) per explicit
// substep; an implicit step also refreshes the solver's rest copies whole (O(springs), small beside its sweeps).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "drape/errors.hpp"
#include "drape/simulation.hpp"
#include "implicit_solver.hpp"

namespace drape {

namespace {
/// The length of seam k (m), in double, from positions x, y, z.
double seam_length(const SeamSet& s, std::size_t k, const float* x, const float* y, const float* z) {
    const double dx = double(x[s.b[k]]) - x[s.a[k]], dy = double(y[s.b[k]]) - y[s.a[k]],
                 dz = double(z[s.b[k]]) - z[s.a[k]];
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}
/// The seam farthest from its rest length (rest(k)) among those `counted` takes, and how many of them are farther
/// than `limit` (> 0 off: longer than its rest, < 0: shorter).
struct SeamOffset {
    double off = 0.0;
    std::size_t at = 0, beyond = 0;
};
template <class Rest, class Counted>
SeamOffset worst_seam_offset(const SeamSet& s, const float* x, const float* y, const float* z, Rest rest,
                             Counted counted, double limit) {
    SeamOffset w;
    for (std::size_t k = 0; k < s.a.size(); ++k) {
        if (!counted(k)) continue;
        const double off = seam_length(s, k, x, y, z) - rest(k);
        if (!(std::fabs(off) <= limit)) ++w.beyond;
        if (std::fabs(off) > std::fabs(w.off)) w.off = off, w.at = k;
    }
    return w;
}
} // namespace

// Without sewing a seam is at its rest length from the start. One that starts open (two panels placed apart) then
// closes in a step or two, and its stretch energy flings the cloth: two canvas panels sewn across a 0.3 m gap reached
// 3,960 m/s and a structural strain of 12.7 in 1 s, within the health monitor's bounds, which include the energy the
// start holds, and the canvas bag's seams, 5 mm open, flung its particles at 182 m/s in the first substep. So with
// sewing off (speed 0: at the start, or switched off while a seam is still closing) a seam more than unsewn_gap_ratio
// times the cloth's spacing (cloth_spacing: its mean structural spring) longer than its rest length is refused, with
// the remedy; so is a saved seam_rest more than saved_seam_rest_ratio times the spacing from its seam's length (the
// cloth lags its schedule by millimetres; shorter would snap the seam shut, longer push the panels apart: 100 m was
// taken).
void Simulation::refuse_seams_off_schedule(const float* x, const float* y, const float* z,
                                           std::span<const float> saved_rest) const {
    const SeamSet& s = cloth_.seams;
    const double spacing = cloth_spacing(cloth_);
    const double ratio = saved_rest.empty() ? double(SimulationParams::unsewn_gap_ratio)
                                            : double(SimulationParams::saved_seam_rest_ratio);
    const double limit = ratio * spacing;
    const SeamOffset w = worst_seam_offset(
        s, x, y, z, [&](std::size_t k) { return saved_rest.empty() ? double(s.rest[k]) : double(saved_rest[k]); },
        [](std::size_t) { return true; }, limit);
    if (w.beyond == 0) return;
    const bool open = w.off > 0.0; // else pushed apart
    char text[720];
    if (saved_rest.empty())
        std::snprintf(text, sizeof text,
                      "a seam is %.3g m %s (particles %u and %u) and the sewing speed is 0, so it would %s in one step "
                      "and fling the cloth; set a sewing speed (physics.sewing_speed, allowed (0, 10] m/s; leave it "
                      "out for the default 0.5) to %s, or place the panels %s: without sewing a seam may be at most "
                      "%.3g m %s (%g x the cloth's spacing)",
                      std::fabs(w.off), open ? "open" : "shorter than its rest length", unsigned(s.a[w.at]),
                      unsigned(s.b[w.at]), open ? "snap shut" : "push the panels apart",
                      open ? "draw the seams shut" : "let the seams out",
                      open ? "closer" : "at the seams' rest length", limit,
                      open ? "open" : "shorter than its rest", ratio);
    else
        std::snprintf(text, sizeof text,
                      "initial state seam_rest[%zu] = %.4g m is %.3g m %s than that seam (particles %u and %u), so it "
                      "would %s; a saved seam's current rest length lies within %.3g m (%g x the cloth's spacing) of "
                      "its length (state.seam_rest in scene files; leave it out to start sewing from the positions)",
                      w.at, double(saved_rest[w.at]), std::fabs(w.off), open ? "shorter" : "longer",
                      unsigned(s.a[w.at]), unsigned(s.b[w.at]),
                      open ? "snap shut and fling the cloth" : "push the panels apart", limit, ratio);
    throw InvalidInput(text);
}

// A seam both of whose ends are pinned never closes (nor opens): pins hold it at its start length. Sewn, the seams
// beside it pull the panels together against the pins and stretch the cloth between them without bound: the canvas
// bag's two panels placed 2 m apart, pinned along their top edges, reached structural strain 16.7 in 100 implicit
// steps, "healthy" (the health monitor's strain bound is 50 without a strain limit). Refused where such a seam starts
// more than saved_seam_rest_ratio spacings off its rest length (the bag as shipped holds its two top corners 5 mm
// off, a spacing of 2 cm).
void Simulation::refuse_seams_held_apart(const InitialState& initial) const {
    const SeamSet& s = cloth_.seams;
    const double limit = double(SimulationParams::saved_seam_rest_ratio) * cloth_spacing(cloth_);
    const float* w = cloth_.inv_mass.data();
    const SeamOffset held = worst_seam_offset(
        s, initial.x.data(), initial.y.data(), initial.z.data(), [&](std::size_t k) { return double(s.rest[k]); },
        [&](std::size_t k) { return w[s.a[k]] == 0.0f && w[s.b[k]] == 0.0f; }, limit);
    if (held.beyond == 0) return;
    char text[640];
    std::snprintf(text, sizeof text,
                  "a seam joins two pinned particles (%u and %u) %.3g m %s than its rest length of %.3g m (%zu such "
                  "seam%s): the pins hold it there, so it never %s, and the seams beside it would stretch the cloth "
                  "between the pins without bound; unpin one panel's edge (cloth.pins) or place the panels so that a "
                  "seam between pinned particles starts within %.3g m of its rest length (%g x the cloth's spacing)",
                  unsigned(s.a[held.at]), unsigned(s.b[held.at]), std::fabs(held.off),
                  held.off > 0.0 ? "longer" : "shorter", double(s.rest[held.at]), held.beyond,
                  held.beyond == 1 ? "" : "s", held.off > 0.0 ? "closes" : "reaches it", limit,
                  double(SimulationParams::saved_seam_rest_ratio));
    throw InvalidInput(text);
}

void Simulation::cook_sewing(const InitialState& initial) {
    const SeamSet& s = cloth_.seams;
    if (s.empty()) return;
    if (!initial.seam_rest.empty() && initial.seam_rest.size() != s.a.size())
        throw InvalidInput("initial state seam_rest has " + std::to_string(initial.seam_rest.size()) +
                           " entries, expected one per seam (" + std::to_string(s.a.size()) + ")");
    refuse_seams_held_apart(initial);
    seam_rest_ = s.rest;
    const bool sew = params_.sewing_speed > 0.0f;
    for (std::size_t k = 0; k < initial.seam_rest.size() && sew; ++k)
        if (!(std::isfinite(initial.seam_rest[k]) && initial.seam_rest[k] > 0.0f))
            throw InvalidInput("initial state seam_rest[" + std::to_string(k) + "] is " +
                               std::to_string(initial.seam_rest[k]) + " (must be a finite length > 0 m)");
    if (!sew || !initial.seam_rest.empty())
        refuse_seams_off_schedule(initial.x.data(), initial.y.data(), initial.z.data(),
                                  sew ? std::span<const float>(initial.seam_rest) : std::span<const float>());
    for (std::size_t k = 0; k < s.a.size() && sew; ++k) {
        float start = 0.0f;
        if (!initial.seam_rest.empty()) {
            start = initial.seam_rest[k]; // a saved state: sewing resumes where it was
        } else {
            start = static_cast<float>(seam_length(s, k, initial.x.data(), initial.y.data(), initial.z.data()));
        }
        // A seam that starts shorter than its rest (panels placed closer than it) is let out to it the same way; its
        // schedule starts at least 1 % of its rest length from zero (a current rest of 0 has no strain).
        seam_rest_[k] = std::max(start, 0.01f * s.rest[k]);
        sewing_ = sewing_ || seam_rest_[k] != s.rest[k];
    }
    edge_rest_.resize(cloth_.edges.size());
    for (std::size_t e = 0; e < cloth_.edges.size(); ++e) edge_rest_[e] = cloth_.edges[e].rest;
    for (std::size_t k = 0; k < s.a.size(); ++k) edge_rest_[s.groups.edge_index[k]] = seam_rest_[k];
}

void Simulation::update_sewing() {
    if (!sewing_) return;
    // One step of the schedule, in float: the same arithmetic whether the run was saved and resumed or not.
    const SeamSet& s = cloth_.seams;
    // Sewing switched off mid-run (set_params): the seams go to their rest length at once, as unsewn seams do.
    const float closing = params_.sewing_speed > 0.0f ? params_.sewing_speed * params_.dt
                                                      : std::numeric_limits<float>::infinity();
    bool open = false;
    for (std::size_t k = 0; k < s.a.size(); ++k) {
        const float target = s.rest[k], now = seam_rest_[k];
        const float rest = now > target ? std::max(target, now - closing) : std::min(target, now + closing);
        open = open || rest != target;
        seam_rest_[k] = rest;
        edge_rest_[s.groups.edge_index[k]] = rest;
    }
    for (std::size_t k = 0; k < limit_seam_slot_.size(); ++k)
        limit_rest_[limit_seam_slot_[k]] = edge_rest_[limit_seam_edge_[k]];
    if (implicit_) implicit_->fine.set_spring_rest(edge_rest_);
    sewing_ = open;
}

} // namespace drape
