// The Kinect source of esf live (live_source.hpp) through libfreenect; built only when
// libfreenect is found (kinect_source_missing.cpp otherwise).
//
// One thread runs the driver (freenect_process_events_timeout in a loop); its callbacks copy
// each depth frame, with the last colour frame, into a one-frame slot that next() takes. Under
// fakenect (libfreenect-bin 0.5.3) each driver call serves one line of the recording's
// INDEX.txt, after waiting the recorded time since the previous line, and at the end of the
// recording it prints "Warning: No more lines in [DIR]" on stdout and returns -1 (again on
// every later call: it neither loops nor ends the program); a missing or unreadable file makes
// it print an error on stdout and call exit(1), which is why the recording is checked here
// first.

#include <dlfcn.h>
#include <libfreenect.h>
#include <sys/time.h>

#include <atomic>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "esf/io/kinect_raw.hpp"
#include "live_source.hpp"

namespace esf::cli {

namespace {

/// What the driver thread and the consumer share; owned by both, so that a driver thread
/// left running after stop() never touches freed memory.
struct DriverState {
    std::mutex mutex;
    std::condition_variable changed;
    KinectFrame pending;
    bool has_pending = false;
    std::size_t skipped = 0;
    std::vector<std::uint8_t> last_rgb;
    double start = -1.0;
    bool ended = false;   // the recording ended (fakenect)
    bool failed = false;  // the device failed
    std::string message;
    bool finished = false;  // the driver thread returned
    std::atomic<bool> stop{false};
    bool fakenect = false;
    freenect_context* context = nullptr;
    freenect_device* device = nullptr;
};

double seconds_now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

void on_depth(freenect_device* device, void* depth, std::uint32_t timestamp) {
    auto* state = static_cast<DriverState*>(freenect_get_user(device));
    const auto* values = static_cast<const std::uint16_t*>(depth);
    std::lock_guard lock(state->mutex);
    if (state->has_pending) ++state->skipped;
    const double now = seconds_now();
    if (state->start < 0.0) state->start = now;
    state->pending.time = now - state->start;
    state->pending.timestamp = timestamp;
    state->pending.depth.assign(values, values + kKinectFramePixels);
    state->pending.rgb = state->last_rgb;
    state->has_pending = true;
    state->changed.notify_all();
}

void on_video(freenect_device* device, void* rgb, std::uint32_t) {
    auto* state = static_cast<DriverState*>(freenect_get_user(device));
    const auto* bytes = static_cast<const std::uint8_t*>(rgb);
    std::lock_guard lock(state->mutex);
    state->last_rgb.assign(bytes, bytes + 3 * kKinectFramePixels);
}

void run_driver(std::shared_ptr<DriverState> state) {
    int status = 0;
    while (!state->stop.load()) {
        timeval timeout{0, 100000};
        status = freenect_process_events_timeout(state->context, &timeout);
        if (status < 0) break;
    }
    std::lock_guard lock(state->mutex);
    if (status < 0) {
        if (state->fakenect) {
            state->ended = true;
        } else {
            state->failed = true;
            state->message =
                "the Kinect stopped: libfreenect error " + std::to_string(status) + " (unplugged?)";
        }
    }
    state->finished = true;
    state->changed.notify_all();
}

/// Fakenect reads past the end of a short frame file and exits on a missing one: check the
/// recording first, with the project's reader, and the size of every frame file.
void check_fakenect_recording() {
    const char* path = std::getenv("FAKENECT_PATH");
    if (!path || !*path)
        throw std::runtime_error(
            "fakenect needs FAKENECT_PATH: the folder of a recording (fakenect-record, esf "
            "record-scenes), e.g. fakenect DIR esf live DB");
    const KinectRecordingReader reader(path);
    for (const KinectRecordingEntry& e : reader.entries()) {
        if (e.type == 'a') continue;
        const auto file = std::filesystem::path(path) / e.file;
        const std::uintmax_t need =
            e.type == 'd' ? 17 + 2 * kKinectFramePixels : 15 + 3 * kKinectFramePixels;
        if (std::filesystem::file_size(file) < need)
            throw std::runtime_error(
                file.string() + ": truncated: " + std::to_string(std::filesystem::file_size(file)) +
                " of " + std::to_string(need) + " bytes");
    }
}

class KinectSource final : public FrameSource {
  public:
    KinectSource(std::shared_ptr<DriverState> state, int device)
        : state_(std::move(state)), device_(device) {
        thread_ = std::thread(run_driver, state_);
    }
    ~KinectSource() override { stop(); }

    FrameWait next(KinectFrame& frame, std::chrono::milliseconds timeout) override {
        std::unique_lock lock(state_->mutex);
        state_->changed.wait_for(lock, timeout,
                                 [&] { return state_->has_pending || state_->finished; });
        if (state_->has_pending) {
            frame = std::move(state_->pending);
            state_->has_pending = false;
            return FrameWait::kFrame;
        }
        if (state_->failed) return FrameWait::kFailed;
        if (state_->finished) return FrameWait::kEnded;
        return FrameWait::kTimeout;
    }
    std::size_t skipped() const override {
        std::lock_guard lock(state_->mutex);
        return state_->skipped;
    }
    std::string message() const override {
        std::lock_guard lock(state_->mutex);
        return state_->message;
    }
    std::string name() const override {
        if (state_->fakenect) {
            const char* path = std::getenv("FAKENECT_PATH");
            return std::string("fakenect recording ") + (path ? path : "");
        }
        return "Kinect " + std::to_string(device_);
    }
    bool stop() override {
        if (stopped_) return clean_;
        stopped_ = true;
        state_->stop.store(true);
        {
            std::unique_lock lock(state_->mutex);
            clean_ = state_->changed.wait_for(lock, std::chrono::seconds(1),
                                              [&] { return state_->finished; });
        }
        if (!clean_) {
            thread_.detach();  // blocked in the driver: left to end with the program
            return false;
        }
        thread_.join();
        freenect_stop_depth(state_->device);
        freenect_stop_video(state_->device);
        freenect_close_device(state_->device);
        freenect_shutdown(state_->context);
        return true;
    }

  private:
    std::shared_ptr<DriverState> state_;
    int device_;
    std::thread thread_;
    bool stopped_ = false;
    bool clean_ = false;
};

}  // namespace

bool kinect_supported() { return true; }

bool kinect_driver_is_fakenect() {
    Dl_info info{};
    if (!dladdr(reinterpret_cast<void*>(&freenect_init), &info) || !info.dli_fname) return false;
    return std::strstr(info.dli_fname, "/fakenect/") != nullptr;
}

std::unique_ptr<FrameSource> open_kinect_source(int device) {
    auto state = std::make_shared<DriverState>();
    state->fakenect = kinect_driver_is_fakenect();
    if (state->fakenect) check_fakenect_recording();
    if (freenect_init(&state->context, nullptr) < 0 || !state->context)
        throw std::runtime_error("libfreenect cannot start (no USB access?)");
    freenect_set_log_level(state->context, FREENECT_LOG_ERROR);
    freenect_select_subdevices(state->context, FREENECT_DEVICE_CAMERA);
    const int devices = freenect_num_devices(state->context);
    if (devices <= 0) {
        freenect_shutdown(state->context);
        throw std::runtime_error(
            "no Kinect found (libfreenect sees no device; is it plugged in "
            "and powered, and may this user open it?)");
    }
    if (device >= devices) {
        freenect_shutdown(state->context);
        throw std::runtime_error("no Kinect " + std::to_string(device) + ": libfreenect sees " +
                                 std::to_string(devices) + " device" + (devices > 1 ? "s" : ""));
    }
    if (freenect_open_device(state->context, &state->device, device) < 0) {
        freenect_shutdown(state->context);
        throw std::runtime_error("Kinect " + std::to_string(device) +
                                 " cannot be opened (in use, or no permission)");
    }
    freenect_set_user(state->device, state.get());
    freenect_set_depth_callback(state->device, on_depth);
    freenect_set_video_callback(state->device, on_video);
    if (freenect_set_depth_mode(
            state->device,
            freenect_find_depth_mode(FREENECT_RESOLUTION_MEDIUM, FREENECT_DEPTH_11BIT)) < 0 ||
        freenect_set_video_mode(state->device, freenect_find_video_mode(FREENECT_RESOLUTION_MEDIUM,
                                                                        FREENECT_VIDEO_RGB)) < 0 ||
        freenect_start_depth(state->device) < 0 || freenect_start_video(state->device) < 0) {
        freenect_close_device(state->device);
        freenect_shutdown(state->context);
        throw std::runtime_error("Kinect " + std::to_string(device) +
                                 " refuses the 640 x 480 11-bit depth and RGB modes");
    }
    return std::make_unique<KinectSource>(std::move(state), device);
}

}  // namespace esf::cli
