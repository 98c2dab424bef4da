// Recording the viewer: a PNG sequence (a directory) or an H.264 video (a path ending in .mp4, through
// Debian's ffmpeg when it is on PATH).
//
// The UI thread reads each frame back (glReadPixels into one of `slot_count` buffers allocated when the
// recording starts) and hands it over; a writer thread encodes the PNG (stb_image_write) or writes the raw
// RGB frame into ffmpeg's stdin (popen of `ffmpeg -f rawvideo -pix_fmt rgb24 -s WxH -r 60 -i - -pix_fmt
// yuv420p FILE`). Encoding never runs on the UI thread; when the writer falls `slot_count` frames behind,
// the UI thread waits for it (no frame is dropped, so a recording has every frame drawn). The first write
// error stops the writer; error() reports it, naming the file. No OpenGL here.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdio>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace drape::app {

/// Whether `program` is an executable file in a directory of $PATH.
bool on_path(const std::string& program);

class FrameRecorder {
  public:
    static constexpr std::size_t slot_count = 4;

    /// target: a directory (created if needed) for frame_00000.png, frame_00001.png, ...; or a file whose
    /// name ends in ".mp4" for a 60 FPS video (needs ffmpeg on PATH; width and height are rounded down to
    /// even numbers, as yuv420p needs). Throws InvalidInput with one line naming the target on failure.
    FrameRecorder(std::string target, int width, int height);
    /// Finishes (waits for the writer, closes ffmpeg).
    ~FrameRecorder();
    FrameRecorder(const FrameRecorder&) = delete;
    FrameRecorder& operator=(const FrameRecorder&) = delete;

    bool video() const noexcept { return video_; }
    const std::string& target() const noexcept { return target_; }
    /// Size of the recorded frames, pixels.
    int width() const noexcept { return width_; }
    int height() const noexcept { return height_; }

    /// A free buffer for the next frame (width() * height() * 3 bytes, rows top first); waits while every
    /// slot is queued. Returns nullptr once the recording failed.
    std::vector<unsigned char>* acquire();
    /// Queues the buffer acquire() returned, filled.
    void submit(std::vector<unsigned char>* frame);
    /// Waits for every queued frame and closes the output; returns error() (empty when all went well).
    std::string finish();

    /// The first write error, one line naming the file ("" while all is well).
    std::string error() const;
    /// Frames written so far (by the writer thread).
    std::size_t frames_written() const;

  private:
    void writer_loop();
    void write_frame(const std::vector<unsigned char>& rgb, std::size_t index);

    std::string target_;
    bool video_ = false;
    int width_ = 0, height_ = 0;
    std::FILE* pipe_ = nullptr;
    std::string ffmpeg_log_; ///< ffmpeg's stderr (a temp file, removed by finish())
    std::vector<std::vector<unsigned char>> slots_;
    std::vector<std::vector<unsigned char>*> free_;
    std::deque<std::vector<unsigned char>*> queued_;
    mutable std::mutex mutex_;
    std::condition_variable changed_;
    bool stop_ = false;
    bool finished_ = false;
    std::string error_;
    std::size_t written_ = 0;
    std::thread writer_;
};

} // namespace drape::app
