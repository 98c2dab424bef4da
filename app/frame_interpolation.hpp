// Steps that take longer than a frame: what the viewer draws between them.
//
// When the simulation's step takes longer than drawing a frame (an implicit step of a 316 x 316 cloth takes ~60 ms
// on this machine's 2 cores, a frame ~30 ms), the viewer no longer waits for the step: it keeps drawing while the
// step runs on its own thread, and each drawn frame blends the last two states the steps produced, so the cloth
// moves smoothly at the frame rate, one step behind the simulation (the render interpolation of fixed-step games).
//
// Each state is a whole ring region of vertex data (the output stage's six planes, x y z nx ny nz, and the strain
// plane: render/cloth_renderer.hpp), published once per step into to(). The drawn frame k after a step arrived
// (k = 0 on the frame that took it) is
//
//     from + alpha (to - from),    alpha = min(1, (k + 1) / F),
//
// F the frames per step (a running mean of the frames between arrivals, so alpha reaches 1 just as the next step
// is due); at an arrival `from` becomes what was drawn last, so the picture never jumps. When steps arrive every
// frame F = 1 and every frame draws the newest state as it is (alpha = 1), as without this stage. Blended normals
// are not unit length: the cloth's shaders normalise them. No OpenGL here; no allocation after resize().
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace drape::app {

class FrameInterpolator {
  public:
    /// New vertex data of `floats` floats per state (a new cloth): both states zero, the next frame snaps.
    void resize(std::size_t floats);
    std::size_t floats() const noexcept { return to_.size(); }

    /// A step finished: what was drawn last becomes the start of the blend, and the frames since the last arrival
    /// update the frames per step. Returns the state to publish the new step into (drawn from the next write()).
    std::span<float> arrival();
    /// The state changed without a step (paused, a reset, a new cloth, the first frame): returns the state to
    /// publish it into; the next write() draws it as it is, and the frames-per-step count starts again.
    std::span<float> snap();

    /// One drawn frame: writes the blend of the two states into out (floats() floats) and returns its alpha.
    float write(std::span<float> out);

    /// The running mean of frames per step (1 while steps arrive every frame).
    double frames_per_step() const noexcept { return frames_per_step_; }
    /// Frames written since the last arrival or snap.
    std::uint32_t frames_since_arrival() const noexcept { return frames_since_; }

    /// Weight of the newest count in the running mean of frames per step.
    static constexpr double mean_weight = 0.25;

  private:
    std::vector<float> from_, to_;
    double frames_per_step_ = 1.0;
    std::uint32_t frames_since_ = 0;
    float alpha_ = 1.0f;   ///< of the last write()
    bool counting_ = false; ///< frames_since_ counts frames between two arrivals (not since a snap)
};

} // namespace drape::app
