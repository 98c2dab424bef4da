#include "frame_interpolation.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace drape::app {

void FrameInterpolator::resize(std::size_t floats) {
    from_.assign(floats, 0.0f);
    to_.assign(floats, 0.0f);
    frames_per_step_ = 1.0;
    frames_since_ = 0;
    alpha_ = 1.0f;
    counting_ = false;
}

std::span<float> FrameInterpolator::arrival() {
    if (alpha_ >= 1.0f) {
        from_.swap(to_); // what was drawn last is the newest state: no blend to keep
    } else {
        for (std::size_t i = 0; i < to_.size(); ++i) from_[i] += alpha_ * (to_[i] - from_[i]);
    }
    if (counting_)
        frames_per_step_ += mean_weight * (double(std::max<std::uint32_t>(frames_since_, 1)) - frames_per_step_);
    counting_ = true;
    frames_since_ = 0;
    alpha_ = 0.0f;
    return to_;
}

std::span<float> FrameInterpolator::snap() {
    frames_since_ = 0;
    alpha_ = 1.0f;
    counting_ = false;
    return to_;
}

float FrameInterpolator::write(std::span<float> out) {
    if (out.size() != to_.size())
        throw std::logic_error("FrameInterpolator::write: " + std::to_string(out.size()) + " floats given, " +
                               std::to_string(to_.size()) + " held");
    // The snap's alpha stays 1; after an arrival alpha climbs by 1 / F a frame.
    const float alpha = counting_ ? static_cast<float>(std::min(1.0, double(frames_since_ + 1) / frames_per_step_))
                                  : 1.0f;
    if (alpha >= 1.0f) {
        std::copy(to_.begin(), to_.end(), out.begin());
    } else {
        const float* a = from_.data();
        const float* b = to_.data();
        float* o = out.data();
        for (std::size_t i = 0; i < to_.size(); ++i) o[i] = a[i] + alpha * (b[i] - a[i]);
    }
    alpha_ = alpha;
    ++frames_since_;
    return alpha;
}

} // namespace drape::app
