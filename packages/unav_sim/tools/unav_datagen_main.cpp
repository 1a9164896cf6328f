// unav datagen SPEC.yaml --samples N --out DIR: randomized samples rendered in process, locally
// over --jobs processes or as a Slurm job array (--backend slurm). Resumable: finished samples
// (manifest.json present) are skipped. Ctrl-C: finished samples stay valid, the interrupted ones
// stay as .sample_*.partial (incomplete; removed when the sweep is resumed).
#include <CLI/CLI.hpp>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "unav_common/crash_report.hpp"
#include "unav_common/errors.hpp"
#include "unav_datagen/dataset_writer.hpp"
#include "unav_datagen/randomization.hpp"
#include "unav_sim/datagen.hpp"

namespace fs = std::filesystem;
using unav::datagen::RandomizationSpec;

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

struct Options {
  std::string spec, out;
  std::uint64_t samples = 1, start = 0;
  int jobs = 1;
  std::string backend = "local";
  bool contact_sheet = false, spec_help = false, wait = false;
  // internal / Slurm task
  long long only_sample = -1;
  long long array_task = -1, array_size = 0;
  std::string slurm_partition;
};

std::string exe_path() {
  char buf[4096] = {};
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  return n > 0 ? std::string(buf, static_cast<size_t>(n)) : "unav_datagen";
}

std::string hms(double s) {
  if (!std::isfinite(s) || s < 0) return "--:--:--";
  char b[32];
  const auto t = static_cast<long long>(s);
  std::snprintf(b, sizeof(b), "%02lld:%02lld:%02lld", t / 3600, t / 60 % 60, t % 60);
  return b;
}

// One line of progress: samples done, frames/s, ETA; redrawn in place on a terminal.
class Progress {
 public:
  Progress(std::uint64_t total_samples, std::uint64_t frames_per_sample)
      : total_(total_samples), fps_(frames_per_sample), tty_(isatty(STDOUT_FILENO)) {}
  void frame() {
    ++frames_;
    draw(false);
  }
  void sample_done() {
    ++done_;
    draw(true);
  }
  void skipped(std::uint64_t n) { skipped_ = n; }
  void draw(bool force) {
    const auto now = std::chrono::steady_clock::now();
    if (!force && now - last_ < std::chrono::milliseconds(250)) return;
    last_ = now;
    const double el = std::chrono::duration<double>(now - start_).count();
    const double rate = el > 0 ? static_cast<double>(frames_) / el : 0.0;
    const double left =
        static_cast<double>((total_ - done_) * fps_) - static_cast<double>(frames_ % std::max<std::uint64_t>(fps_, 1));
    const double eta = rate > 0 ? left / rate : NAN;
    const int width = 30;
    const int fill =
        total_ ? static_cast<int>(width * static_cast<double>(done_) / static_cast<double>(total_)) : width;
    char line[256];
    std::snprintf(line, sizeof(line), "[%s%s] %llu/%llu samples | %.1f frames/s | ETA %s",
                  std::string(fill, '#').c_str(), std::string(width - fill, '.').c_str(),
                  static_cast<unsigned long long>(done_), static_cast<unsigned long long>(total_), rate,
                  hms(eta).c_str());
    if (tty_) {
      std::printf("\r%s", line);
      std::fflush(stdout);
    } else if (force) {
      std::printf("%s\n", line);
      std::fflush(stdout);
    }
  }
  void finish() {
    if (tty_) std::printf("\n");
  }
  std::uint64_t frames() const { return frames_; }
  double elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

 private:
  std::uint64_t total_, fps_, done_ = 0, frames_ = 0, skipped_ = 0;
  bool tty_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_{};
};

// Samples [start, start + n) not finished yet; stale .partial folders of the sweep removed.
std::vector<std::uint64_t> pending(const Options& o) {
  std::vector<std::uint64_t> out;
  for (std::uint64_t i = o.start; i < o.start + o.samples; ++i)
    if (!unav::sim::sample_finished(o.out, i)) out.push_back(i);
  return out;
}

void remove_partials(const Options& o, const std::vector<std::uint64_t>& todo) {
  for (const auto i : todo) fs::remove_all(fs::path(o.out) / ("." + unav::sim::sample_name(i) + ".partial"));
}

// Runs the given samples here, one after the other.
int run_inline(const RandomizationSpec& spec, const Options& o, const std::vector<std::uint64_t>& todo, bool report) {
  Progress prog(todo.size(), static_cast<std::uint64_t>(spec.sample(0).output.frames));
  for (const auto i : todo) {
    const auto r = unav::sim::generate_sample(spec, i, o.out, &g_stop, [&](std::uint64_t) {
      if (report) {
        std::printf("F\n");  // one line per frame for the parent's progress bar
        std::fflush(stdout);
      } else {
        prog.frame();
      }
    });
    if (!r.finished) {
      if (!report) prog.finish();
      std::cerr << "unav datagen: interrupted: " << unav::sim::sample_name(i) << " left incomplete (" << r.frames
                << " frames, ." << unav::sim::sample_name(i) << ".partial)" << std::endl;
      return 130;
    }
    if (!report) prog.sample_done();
  }
  if (!report) {
    prog.finish();
    std::printf("unav datagen: %zu samples, %llu frames in %.1f s (%.2f frames/s)\n", todo.size(),
                static_cast<unsigned long long>(prog.frames()), prog.elapsed(),
                static_cast<double>(prog.frames()) / std::max(1e-9, prog.elapsed()));
  }
  return 0;
}

// Runs the samples over `jobs` child processes (one sample each), with a progress bar.
int run_local_jobs(const RandomizationSpec& spec, const Options& o, const std::vector<std::uint64_t>& todo) {
  struct Child {
    pid_t pid;
    int fd;
    std::uint64_t index;
    std::string buf;
  };
  Progress prog(todo.size(), static_cast<std::uint64_t>(spec.sample(0).output.frames));
  std::vector<Child> running;
  size_t next = 0;
  int failures = 0;
  const std::string exe = exe_path();
  while ((next < todo.size() && !g_stop) || !running.empty()) {
    while (!g_stop && next < todo.size() && static_cast<int>(running.size()) < o.jobs) {
      int fds[2];
      if (pipe(fds) != 0) throw std::runtime_error("pipe failed");
      const pid_t pid = fork();
      if (pid == 0) {
        dup2(fds[1], STDOUT_FILENO);
        close(fds[0]);
        close(fds[1]);
        const std::string idx = std::to_string(todo[next]);
        execl(exe.c_str(), exe.c_str(), o.spec.c_str(), "--out", o.out.c_str(), "--only-sample", idx.c_str(),
              static_cast<char*>(nullptr));
        _exit(127);
      }
      close(fds[1]);
      running.push_back({pid, fds[0], todo[next], ""});
      ++next;
    }
    std::vector<pollfd> pfds;
    pfds.reserve(running.size());
    for (const auto& c : running) pfds.push_back({c.fd, POLLIN, 0});
    poll(pfds.data(), pfds.size(), 200);
    for (size_t k = 0; k < running.size();) {
      Child& c = running[k];
      char buf[4096];
      bool eof = false;
      if (pfds[k].revents & (POLLIN | POLLHUP)) {
        const ssize_t n = read(c.fd, buf, sizeof(buf));
        if (n <= 0) eof = true;
        for (ssize_t j = 0; j < n; ++j)
          if (buf[j] == 'F') prog.frame();
      }
      if (!eof) {
        ++k;
        continue;
      }
      close(c.fd);
      int status = 0;
      waitpid(c.pid, &status, 0);
      if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
        prog.sample_done();
      } else if (!g_stop) {
        ++failures;
        std::cerr << "\nunav datagen: " << unav::sim::sample_name(c.index) << " failed (exit "
                  << (WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status)) << ")" << std::endl;
      }
      running.erase(running.begin() + static_cast<std::ptrdiff_t>(k));
      pfds.erase(pfds.begin() + static_cast<std::ptrdiff_t>(k));
    }
    if (g_stop)
      for (const auto& c : running) kill(c.pid, SIGINT);
  }
  prog.finish();
  if (g_stop) {
    std::cerr << "unav datagen: interrupted; finished samples are valid, the unfinished ones are .partial" << std::endl;
    return 130;
  }
  std::printf("unav datagen: %zu samples, %llu frames in %.1f s (%.2f frames/s, %d jobs)\n", todo.size(),
              static_cast<unsigned long long>(prog.frames()), prog.elapsed(),
              static_cast<double>(prog.frames()) / std::max(1e-9, prog.elapsed()), o.jobs);
  return failures ? 1 : 0;
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char ch : s) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return q + "'";
}

// The sweep as a Slurm job array: each task runs its share of the samples.
int run_slurm(const RandomizationSpec& spec, const Options& o, const std::vector<std::uint64_t>& todo) {
  const unav::datagen::SlurmResources sl = spec.sample(0).slurm;
  const long long tasks = std::min<long long>(static_cast<long long>(o.samples),
                                              sl.array_size > 0 ? sl.array_size : static_cast<long long>(o.samples));
  if (tasks < 1) throw unav::ConfigError(spec.file(), "--samples", std::to_string(o.samples), "must be >= 1");
  const fs::path dir = fs::absolute(fs::path(o.out) / "slurm");
  fs::create_directories(dir);
  const fs::path script = dir / "unav_datagen.sbatch";
  std::ofstream f(script);
  f << "#!/bin/bash\n"
    << "#SBATCH --job-name=unav_datagen\n"
    << "#SBATCH --array=0-" << tasks - 1 << "\n"
    << "#SBATCH --cpus-per-task=" << sl.cpus_per_task << "\n"
    << "#SBATCH --mem=" << sl.mem << "\n"
    << "#SBATCH --time=" << sl.time << "\n"
    << "#SBATCH --output=" << (dir / "task_%A_%a.log").string() << "\n";
  const std::string partition = o.slurm_partition.empty() ? sl.partition : o.slurm_partition;
  if (!partition.empty()) f << "#SBATCH --partition=" << partition << "\n";
  if (!sl.gres.empty()) f << "#SBATCH --gres=" << sl.gres << "\n";
  f << "# Each array task renders the samples i of [" << o.start << ", " << o.start + o.samples
    << ") with (i - start) % " << tasks << " == task; finished samples are skipped.\n"
    << "exec " << shell_quote(exe_path()) << " " << shell_quote(fs::absolute(o.spec).string()) << " --samples "
    << o.samples << " --start " << o.start << " --out " << shell_quote(fs::absolute(o.out).string())
    << " --array-task \"$SLURM_ARRAY_TASK_ID\" --array-size " << tasks << "\n";
  f.close();
  fs::permissions(script, fs::perms::owner_all | fs::perms::group_read | fs::perms::others_read);
  std::printf("unav datagen: %zu of %llu samples to do; job array of %lld tasks: %s\n", todo.size(),
              static_cast<unsigned long long>(o.samples), tasks, script.c_str());
  const std::string cmd =
      std::string("sbatch --parsable") + (o.wait ? " --wait" : "") + " " + shell_quote(script.string());
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) throw std::runtime_error("cannot run sbatch");
  char buf[256] = {};
  std::string job;
  while (fgets(buf, sizeof(buf), p)) job += buf;
  const int rc = pclose(p);
  while (!job.empty() && (job.back() == '\n' || job.back() == ' ')) job.pop_back();
  if (rc != 0) {
    std::cerr << "unav datagen: sbatch failed (exit " << WEXITSTATUS(rc) << ")" << (job.empty() ? "" : ": " + job)
              << std::endl;
    return 1;
  }
  std::printf("unav datagen: submitted job %s%s\n", job.c_str(), o.wait ? " and waited for it" : "");
  if (o.wait) {
    const auto left = pending(o);
    std::printf("unav datagen: %llu/%llu samples finished\n", static_cast<unsigned long long>(o.samples - left.size()),
                static_cast<unsigned long long>(o.samples));
    return left.empty() ? 0 : 1;
  }
  return 0;
}

// A grid of the middle frame of every finished sample, labelled with index, water and path.
void contact_sheet(const RandomizationSpec& spec, const Options& o) {
  std::vector<cv::Mat> tiles;
  const int tw = 320, th = 240;
  for (std::uint64_t i = o.start; i < o.start + o.samples; ++i) {
    if (!unav::sim::sample_finished(o.out, i)) continue;
    const fs::path d = fs::path(o.out) / unav::sim::sample_name(i);
    std::vector<fs::path> images;
    for (const char* sub : {"rgb", "cam0/data", "image_0"})
      if (fs::is_directory(d / sub))
        for (const auto& e : fs::directory_iterator(d / sub))
          if (e.path().extension() == ".png") images.push_back(e.path());
    if (images.empty()) continue;
    std::sort(images.begin(), images.end());
    cv::Mat img = cv::imread(images[images.size() / 2].string(), cv::IMREAD_COLOR);
    if (img.empty()) continue;
    cv::resize(img, img, cv::Size(tw, th), 0, 0, cv::INTER_AREA);
    const unav::datagen::DatagenSample s = spec.sample(i);
    char label[160];
    std::snprintf(label, sizeof(label), "#%llu %s x%.2f %.0fm %s", static_cast<unsigned long long>(i),
                  s.world.water.preset.c_str(), s.world.water.turbidity, s.world.seabed.depth_m,
                  s.trajectory.kind.c_str());
    cv::rectangle(img, cv::Point(0, 0), cv::Point(tw, 18), cv::Scalar(0, 0, 0), cv::FILLED);
    cv::putText(img, label, cv::Point(4, 13), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    tiles.push_back(img);
  }
  if (tiles.empty()) {
    std::cerr << "unav datagen: no finished sample for the contact sheet" << std::endl;
    return;
  }
  const int cols = std::min<int>(4, static_cast<int>(tiles.size()));
  const int rows = (static_cast<int>(tiles.size()) + cols - 1) / cols;
  cv::Mat sheet(rows * th, cols * tw, CV_8UC3, cv::Scalar(40, 40, 40));
  for (size_t k = 0; k < tiles.size(); ++k)
    tiles[k].copyTo(sheet(cv::Rect(static_cast<int>(k % cols) * tw, static_cast<int>(k / cols) * th, tw, th)));
  const std::string path = (fs::path(o.out) / "contact_sheet.png").string();
  if (!cv::imwrite(path, sheet)) throw unav::datagen::DatasetError(path + ": cannot write");
  std::printf("unav datagen: contact sheet of %zu samples: %s\n", tiles.size(), path.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  unav::common::InstallCrashReport("unav datagen");
  CLI::App app{"unav datagen: randomized synthetic datasets (in process), locally or on a Slurm cluster",
               "unav datagen"};
  Options o;
  app.add_option("spec", o.spec, "randomization spec YAML (see --spec-help)");
  app.add_option("--out", o.out, "output folder (samples are sample_000000, ...)");
  app.add_option("-n,--samples", o.samples, "how many samples (default 1)");
  app.add_option("--start", o.start, "index of the first sample (default 0)");
  app.add_option("-j,--jobs", o.jobs, "local processes rendering in parallel (default 1)")->check(CLI::Range(1, 256));
  app.add_option("--backend", o.backend, "local (default) or slurm (a job array through sbatch)")
      ->check(CLI::IsMember({"local", "slurm"}));
  app.add_flag("--wait", o.wait, "slurm: wait for the job array to finish (sbatch --wait)");
  app.add_option("--partition", o.slurm_partition, "slurm: partition (default: the spec's slurm.partition)");
  app.add_flag("--contact-sheet", o.contact_sheet, "write <out>/contact_sheet.png of the finished samples");
  app.add_flag("--spec-help", o.spec_help, "print every key of the spec language and exit");
  app.add_option("--only-sample", o.only_sample, "internal: render one sample, report frames on stdout")->group("");
  app.add_option("--array-task", o.array_task, "slurm task: this task's index")->group("");
  app.add_option("--array-size", o.array_size, "slurm task: number of tasks")->group("");
  CLI11_PARSE(app, argc, argv);
  if (o.spec_help) {
    std::cout << "# unav datagen spec keys\n" << RandomizationSpec::documentation();
    return 0;
  }
  try {
    if (o.spec.empty()) throw unav::ConfigError("a spec file is required (unav datagen SPEC.yaml --out DIR)");
    if (o.out.empty()) throw unav::ConfigError("--out DIR is required");
    const RandomizationSpec spec = RandomizationSpec::load(o.spec);  // every check before any work
    fs::create_directories(o.out);
    {  // the output must be writable before hours of rendering start
      const fs::path probe = fs::path(o.out) / ".unav_write_test";
      std::ofstream t(probe);
      if (!(t << "ok")) throw unav::datagen::DatasetError(o.out + ": not writable");
      t.close();
      fs::remove(probe);
    }
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    if (o.only_sample >= 0) return run_inline(spec, o, {static_cast<std::uint64_t>(o.only_sample)}, true);
    if (o.array_task >= 0) {
      if (o.array_size < 1 || o.array_task >= o.array_size)
        throw unav::ConfigError("--array-task " + std::to_string(o.array_task) + " / --array-size " +
                                std::to_string(o.array_size) + ": need 0 <= task < size");
      std::vector<std::uint64_t> mine;
      for (const auto i : pending(o))
        if (static_cast<long long>((i - o.start) % static_cast<std::uint64_t>(o.array_size)) == o.array_task)
          mine.push_back(i);
      remove_partials(o, mine);
      std::printf("unav datagen: task %lld of %lld: %zu samples\n", o.array_task, o.array_size, mine.size());
      return run_inline(spec, o, mine, false);
    }
    const auto todo = pending(o);
    if (todo.size() < o.samples)
      std::printf("unav datagen: %llu of %llu samples already finished (skipped)\n",
                  static_cast<unsigned long long>(o.samples - todo.size()), static_cast<unsigned long long>(o.samples));
    remove_partials(o, todo);
    int rc = 0;
    if (o.backend == "slurm") {
      rc = run_slurm(spec, o, todo);
    } else if (!todo.empty()) {
      rc = o.jobs == 1 ? run_inline(spec, o, todo, false) : run_local_jobs(spec, o, todo);
    }
    if (o.contact_sheet && rc == 0) contact_sheet(spec, o);
    if (rc == 0 && o.backend == "local") std::printf("unav datagen: samples in %s\n", fs::absolute(o.out).c_str());
    return rc;
  } catch (const unav::ConfigError& e) {
    std::cerr << "unav datagen: error: " << e.what() << std::endl;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "unav datagen: error: " << e.what() << std::endl;
    return 1;
  }
}
