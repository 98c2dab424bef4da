// The viewer's frames between steps longer than a frame (app/frame_interpolation.hpp): what each frame draws.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "frame_interpolation.hpp"

using drape::app::FrameInterpolator;

namespace {

// A state whose every float is `value` (one float per plane would do; a few make the loops' tails run).
void publish(std::span<float> state, float value) {
    for (float& f : state) f = value;
}

// An interpolator of `floats` floats that has drawn a state of zeros into out.
FrameInterpolator started(std::size_t floats, std::vector<float>& out) {
    FrameInterpolator f;
    f.resize(floats);
    out.assign(floats, -1.0f);
    publish(f.snap(), 0.0f);
    f.write(out);
    return f;
}

// Steps first..last (state k is k), each followed by `frames` drawn frames.
void run_steps(FrameInterpolator& f, std::vector<float>& out, int first, int last, int frames) {
    for (int step = first; step <= last; ++step) {
        publish(f.arrival(), float(step));
        for (int k = 0; k < frames; ++k) f.write(out);
    }
}

} // namespace

// Steps that end every frame: each frame draws the newest state exactly, as without interpolation.
TEST(FrameInterpolator, StepsEveryFrameDrawTheNewestStateAsItIs) {
    FrameInterpolator f;
    f.resize(37);
    std::vector<float> out(37, -1.0f);
    publish(f.snap(), 0.0f);
    EXPECT_EQ(f.write(out), 1.0f);
    for (int step = 1; step <= 20; ++step) {
        publish(f.arrival(), 0.1f * float(step) + 1e-3f * float(step * step));
        EXPECT_EQ(f.write(out), 1.0f) << step;
        for (float v : out) ASSERT_EQ(v, 0.1f * float(step) + 1e-3f * float(step * step)) << step;
    }
    EXPECT_DOUBLE_EQ(f.frames_per_step(), 1.0);
}

// Steps that end every third frame: the running mean of frames per step goes to 3, the frames in between climb a
// third of the way each, and the drawn value never jumps back or by more than one step's change.
TEST(FrameInterpolator, StepsOverSeveralFramesAreDrawnBlendedWithoutJumps) {
    std::vector<float> out;
    FrameInterpolator f = started(21, out);
    float last = 0.0f;
    for (int step = 1; step <= 40; ++step) {
        publish(f.arrival(), float(step)); // state k is k: the exact motion is one unit a step
        for (int k = 0; k < 3; ++k) {
            const float alpha = f.write(out);
            for (float v : out) ASSERT_EQ(v, out[0]);
            EXPECT_GE(out[0], last) << "drawn backwards at step " << step;
            EXPECT_LE(out[0] - last, 1.0f + 1e-5f) << "jumped at step " << step;
            EXPECT_GT(alpha, 0.0f);
            if (step > 30) {
                EXPECT_NEAR(alpha, float(k + 1) / 3.0f, 1e-3f) << step << " " << k;
            }
            last = out[0];
        }
    }
    EXPECT_NEAR(f.frames_per_step(), 3.0, 1e-3);
    // Steady: one step behind, moving a third of a step a frame.
    EXPECT_NEAR(out[0], 40.0f, 1e-3f);
    // A step that comes late holds the newest state (alpha 1) until it arrives, and lengthens the mean.
    publish(f.arrival(), 41.0f);
    for (int k = 0; k < 5; ++k) f.write(out);
    EXPECT_EQ(out[0], 41.0f);
    EXPECT_EQ(f.frames_since_arrival(), 5u);
    publish(f.arrival(), 42.0f);
    EXPECT_NEAR(f.frames_per_step(), 3.0 + FrameInterpolator::mean_weight * 2.0, 1e-3);
}

// A step arriving before the blend reached its end starts from what was drawn, not from the older state.
TEST(FrameInterpolator, AnEarlyStepBlendsOnFromWhatWasDrawn) {
    std::vector<float> out;
    FrameInterpolator f = started(5, out);
    run_steps(f, out, 1, 30, 4); // F -> 4
    ASSERT_EQ(out[0], 30.0f);
    publish(f.arrival(), 31.0f);
    f.write(out); // a quarter of the way: 30.25
    EXPECT_NEAR(out[0], 30.25f, 1e-3f);
    publish(f.arrival(), 32.0f); // early
    const float alpha = f.write(out);
    EXPECT_NEAR(out[0], 30.25f + alpha * (32.0f - 30.25f), 1e-4f);
    EXPECT_GT(out[0], 30.25f);
}

// A snap (paused, reset, a new cloth) draws the state as it is at once and restarts the count.
TEST(FrameInterpolator, SnapDrawsAtOnceAndWrongSizesAreRefused) {
    std::vector<float> out;
    FrameInterpolator f = started(8, out);
    run_steps(f, out, 1, 10, 2);
    publish(f.snap(), -7.0f);
    EXPECT_EQ(f.write(out), 1.0f);
    EXPECT_EQ(out[3], -7.0f);
    publish(f.arrival(), 5.0f);
    EXPECT_LT(f.write(out), 1.0f) << "frames per step forgotten by the snap";
    std::vector<float> wrong(9);
    EXPECT_THROW(f.write(wrong), std::logic_error);
    f.resize(9);
    EXPECT_EQ(f.floats(), 9u);
    EXPECT_DOUBLE_EQ(f.frames_per_step(), 1.0);
}
