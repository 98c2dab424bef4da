// Fixed-size, 64-byte-aligned arrays for the hot structure-of-arrays state.
//
// Every hot array may carry a "halo": zero-filled elements before index 0 and after the end. The regular-grid
// kernel reads neighbours at fixed index offsets (up to two grid rows away) with unaligned SIMD loads; the halo
// keeps those reads inside the allocation and finite, and the per-particle neighbour mask discards them.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <span>
#include <utility>

namespace drape {

inline constexpr std::size_t cache_line_bytes = 64;

/// A heap array of trivially copyable T, 64-byte aligned at index 0, with `halo` zeroed elements on both sides.
/// Sized once when a cloth is cooked; never resized in a step.
template <class T> class AlignedArray {
  public:
    AlignedArray() = default;
    AlignedArray(std::size_t count, std::size_t halo = 0) { reset(count, halo); }
    AlignedArray(const AlignedArray& other) { *this = other; }
    AlignedArray(AlignedArray&& other) noexcept { swap(other); }
    AlignedArray& operator=(const AlignedArray& other) {
        if (this != &other) {
            reset(other.count_, other.halo_);
            const std::size_t bytes = (count_ + 2 * halo_) * sizeof(T);
            if (bytes != 0) std::memcpy(base_, other.base_, bytes); // an empty array has no buffer (memcpy(nullptr))
        }
        return *this;
    }
    AlignedArray& operator=(AlignedArray&& other) noexcept {
        AlignedArray tmp(std::move(other));
        swap(tmp);
        return *this;
    }
    ~AlignedArray() { std::free(base_); }

    /// Reallocates to `count` elements plus `halo` on each side (halo rounded up to whole cache lines); all zero.
    void reset(std::size_t count, std::size_t halo = 0) {
        std::free(base_);
        base_ = nullptr;
        constexpr std::size_t per_line = cache_line_bytes / sizeof(T);
        halo = (halo + per_line - 1) / per_line * per_line;
        count_ = count;
        halo_ = halo;
        std::size_t bytes = (count + 2 * halo) * sizeof(T);
        bytes = (bytes + cache_line_bytes - 1) / cache_line_bytes * cache_line_bytes;
        if (bytes == 0) return;
        base_ = static_cast<T*>(std::aligned_alloc(cache_line_bytes, bytes));
        if (!base_) throw std::bad_alloc();
        std::memset(static_cast<void*>(base_), 0, bytes);
    }
    void swap(AlignedArray& other) noexcept {
        std::swap(base_, other.base_);
        std::swap(count_, other.count_);
        std::swap(halo_, other.halo_);
    }

    T* data() noexcept { return base_ + halo_; }
    const T* data() const noexcept { return base_ + halo_; }
    std::size_t size() const noexcept { return count_; }
    std::size_t halo() const noexcept { return halo_; }
    T& operator[](std::size_t i) noexcept { return data()[i]; }
    const T& operator[](std::size_t i) const noexcept { return data()[i]; }
    std::span<T> span() noexcept { return {data(), count_}; }
    std::span<const T> span() const noexcept { return {data(), count_}; }
    T* begin() noexcept { return data(); }
    T* end() noexcept { return data() + count_; }
    const T* begin() const noexcept { return data(); }
    const T* end() const noexcept { return data() + count_; }

  private:
    T* base_ = nullptr;
    std::size_t count_ = 0;
    std::size_t halo_ = 0;
};

} // namespace drape
