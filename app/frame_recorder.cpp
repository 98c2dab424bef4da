#include "frame_recorder.hpp"

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <sys/wait.h>
#include <unistd.h>

#include "drape/errors.hpp"
#include "screenshot.hpp"

namespace drape::app {

namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// The path in single quotes for /bin/sh (a quote inside becomes '\'').
std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) {
        if (c == '\'')
            q += "'\\''";
        else
            q += c;
    }
    return q + "'";
}

/// The last non-empty line of a text file ("" when there is none), without the trailing newline.
std::string last_line(const std::string& path) {
    if (path.empty()) return {};
    std::ifstream in(path);
    std::string line, last;
    while (std::getline(in, line))
        if (!line.empty()) last = line;
    return last;
}

} // namespace

bool on_path(const std::string& program) {
    const char* path = std::getenv("PATH");
    if (!path) return false;
    std::string dirs = path;
    std::size_t start = 0;
    while (start <= dirs.size()) {
        const std::size_t end = std::min(dirs.find(':', start), dirs.size());
        const std::string dir = dirs.substr(start, end - start);
        const std::string candidate = (dir.empty() ? std::string(".") : dir) + "/" + program;
        if (::access(candidate.c_str(), X_OK) == 0 && std::filesystem::is_regular_file(candidate)) return true;
        start = end + 1;
    }
    return false;
}

FrameRecorder::FrameRecorder(std::string target, int width, int height)
    : target_(std::move(target)), video_(ends_with(target_, ".mp4")), width_(width), height_(height) {
    if (target_.empty()) throw InvalidInput("record: no file or directory given");
    if (video_) {
        width_ &= ~1;
        height_ &= ~1;
    }
    if (width_ <= 0 || height_ <= 0) throw InvalidInput("record: the window is too small to record");
    if (video_) {
        if (!on_path("ffmpeg"))
            throw InvalidInput("record: " + target_ +
                               " needs ffmpeg on PATH (apt install ffmpeg), or give a directory for PNG frames");
        const std::filesystem::path parent = std::filesystem::path(target_).parent_path();
        if (!parent.empty() && !std::filesystem::is_directory(parent))
            throw WriteError("record: cannot write '" + target_ + "': no directory '" + parent.string() + "'");
        // ffmpeg exiting early must not kill the viewer with SIGPIPE: writes then fail with EPIPE instead.
        std::signal(SIGPIPE, SIG_IGN);
        // ffmpeg's own messages go to a log file, so a failure is reported as one line naming the target.
        std::string log = (std::filesystem::temp_directory_path() / "drape-ffmpeg-XXXXXX").string();
        const int fd = ::mkstemp(log.data());
        if (fd >= 0) {
            ::close(fd);
            ffmpeg_log_ = log;
        }
        const std::string command = "ffmpeg -loglevel error -nostats -y -f rawvideo -pix_fmt rgb24 -s " +
                                    std::to_string(width_) + "x" + std::to_string(height_) +
                                    " -r 60 -i - -pix_fmt yuv420p " + shell_quote(target_) +
                                    (ffmpeg_log_.empty() ? "" : " 2>" + shell_quote(ffmpeg_log_));
        pipe_ = ::popen(command.c_str(), "w");
        if (!pipe_) {
            std::error_code ec;
            if (!ffmpeg_log_.empty()) std::filesystem::remove(ffmpeg_log_, ec);
            throw WriteError("record: cannot start ffmpeg for '" + target_ + "'");
        }
    } else {
        std::error_code ec;
        std::filesystem::create_directories(target_, ec);
        if (ec || !std::filesystem::is_directory(target_))
            throw WriteError("record: cannot create the directory '" + target_ + "'" +
                               (ec ? ": " + ec.message() : std::string()));
    }
    // Every buffer now: the frame loop allocates nothing while recording.
    slots_.resize(slot_count);
    for (auto& s : slots_) {
        s.resize(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) * 3);
        free_.push_back(&s);
    }
    writer_ = std::thread([this] { writer_loop(); });
}

FrameRecorder::~FrameRecorder() {
    finish();
}

std::vector<unsigned char>* FrameRecorder::acquire() {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return !free_.empty() || !error_.empty() || stop_; });
    if (!error_.empty() || stop_) return nullptr;
    std::vector<unsigned char>* s = free_.back();
    free_.pop_back();
    return s;
}

void FrameRecorder::submit(std::vector<unsigned char>* frame) {
    {
        std::lock_guard lock(mutex_);
        queued_.push_back(frame);
    }
    changed_.notify_all();
}

void FrameRecorder::writer_loop() {
    for (;;) {
        std::vector<unsigned char>* frame = nullptr;
        std::size_t index = 0;
        {
            std::unique_lock lock(mutex_);
            changed_.wait(lock, [&] { return !queued_.empty() || stop_; });
            if (queued_.empty()) return; // stop_ and nothing left
            frame = queued_.front();
            queued_.pop_front();
            index = written_;
            if (!error_.empty()) {
                free_.push_back(frame); // after a failure frames are discarded
                changed_.notify_all();
                continue;
            }
        }
        std::string failure;
        try {
            write_frame(*frame, index);
        } catch (const std::exception& e) {
            failure = e.what();
        }
        {
            std::lock_guard lock(mutex_);
            if (failure.empty())
                ++written_;
            else if (error_.empty())
                error_ = failure;
            free_.push_back(frame);
        }
        changed_.notify_all();
    }
}

void FrameRecorder::write_frame(const std::vector<unsigned char>& rgb, std::size_t index) {
    if (video_) {
        if (std::fwrite(rgb.data(), 1, rgb.size(), pipe_) != rgb.size())
            throw std::runtime_error("cannot write '" + target_ + "': ffmpeg stopped reading");
        return;
    }
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05zu.png", index);
    const std::string path = (std::filesystem::path(target_) / name).string();
    render::write_png_rgb(path, width_, height_, rgb);
}

std::string FrameRecorder::finish() {
    {
        std::lock_guard lock(mutex_);
        if (finished_) return error_;
        finished_ = true;
        stop_ = true;
    }
    changed_.notify_all();
    if (writer_.joinable()) writer_.join();
    if (pipe_) {
        const int status = ::pclose(pipe_);
        pipe_ = nullptr;
        std::lock_guard lock(mutex_);
        const std::string said = last_line(ffmpeg_log_);
        if (status != 0 || !error_.empty()) {
            const int code = status > 0 && WIFEXITED(status) ? WEXITSTATUS(status) : status;
            error_ = "cannot write '" + target_ + "': ffmpeg " +
                     (said.empty() ? "exited with status " + std::to_string(code) : "said: " + said);
        } else if (written_ == 0) {
            error_ = "no frames recorded to '" + target_ + "'";
        }
    }
    if (!ffmpeg_log_.empty()) {
        std::error_code ec;
        std::filesystem::remove(ffmpeg_log_, ec);
    }
    std::lock_guard lock(mutex_);
    return error_;
}

std::string FrameRecorder::error() const {
    std::lock_guard lock(mutex_);
    return error_;
}

std::size_t FrameRecorder::frames_written() const {
    std::lock_guard lock(mutex_);
    return written_;
}

} // namespace drape::app
