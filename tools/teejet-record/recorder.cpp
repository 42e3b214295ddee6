#include "recorder.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <fastdds/dds/core/condition/StatusCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fstream>
#include <iostream>
#include <memory>

#include "teejet/bus_frame/bus_frame.hpp"
#include "teejet/dds/event_watchdog.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/tcp_rejoin.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/mcap/writer.hpp"
#include "teejet/recording/catalog.hpp"
#include "teejet/recording/latest_samples.hpp"

namespace teejet::record {
namespace {

using namespace std::chrono_literals;
using recording::TakenSample;
using recording::TopicType;

// Longest wait between looks at the clock and the stop flag.
constexpr Duration kLongestWait = 100ms;
constexpr Duration kReportPeriod = 1s;
// Samples are written in the order they were received (log time), across topics. A sample is
// taken a little after its reception time, and one topic's reader may be taken later than
// another's (measured: up to 10 ms on a busy 2-core machine), so samples wait this long before
// they are written, and go out sorted.
constexpr std::uint64_t kReorderWindowNs = 100'000'000;

// Log times on a timeline that steps of the wall clock do not move: the wall clock when the
// recording started, then the monotonic clock's progress. A recorder whose clock stepped back an
// hour after 6 s wrote a 14 s file that read as 3,599.97 s long, and replay waited the hour.
// Fast DDS stamps a sample's reception on the wall clock; the sample is placed on the timeline
// by its age when taken (milliseconds), which a step between its reception and the take could
// distort: beyond kLongestAge, or negative, the step is ignored.
class LogTimeline {
 public:
  explicit LogTimeline(const Clock& clock)
      : clock_(clock), wall_start_(unix_nanoseconds(clock.wall())), steady_start_(clock.steady()) {}

  // The timeline now, and the wall clock now, read together.
  struct Now {
    std::uint64_t timeline;
    std::uint64_t wall;
  };
  Now now() const {
    const auto elapsed =
        std::chrono::duration_cast<std::chrono::nanoseconds>(clock_.steady() - steady_start_);
    return {wall_start_ + static_cast<std::uint64_t>(std::max<std::int64_t>(elapsed.count(), 0)),
            unix_nanoseconds(clock_.wall())};
  }

  // Where a sample received at `received_wall` (0: unknown, taken now) goes on the timeline.
  static std::uint64_t place(std::uint64_t received_wall, const Now& now) {
    if (received_wall == 0 || received_wall >= now.wall) return now.timeline;
    return now.timeline - std::min(now.wall - received_wall, kLongestAge);
  }

 private:
  static constexpr std::uint64_t kLongestAge = 10'000'000'000;
  const Clock& clock_;
  const std::uint64_t wall_start_;
  const SteadyTime steady_start_;
};

// Taken, not yet written: ordered by reception time (then by the order taken), with the index of
// the sample's topic.
using Pending = std::multimap<std::uint64_t, std::pair<std::size_t, TakenSample>>;

// The readers of the recorded topics, in the order of their types, and the one WaitSet that wakes
// the recorder's thread when any of them has data.
class TopicReaders {
 public:
  static Result<std::unique_ptr<TopicReaders>> open(dds::Participant& participant,
                                                    const std::vector<std::string>& topics) {
    std::unique_ptr<TopicReaders> readers(new TopicReaders());
    for (const auto& name : topics) {
      const TopicType* type = recording::find_topic(name);
      auto reader = type->open_reader(participant);
      if (!reader) return reader.error();
      auto& condition = (*reader)->reader()->get_statuscondition();
      condition.set_enabled_statuses(eprosima::fastdds::dds::StatusMask::data_available());
      readers->wait_set_.attach_condition(condition);
      readers->types_.push_back(type);
      readers->readers_.push_back(std::move(*reader));
    }
    return readers;
  }

  const std::vector<const TopicType*>& types() const { return types_; }

  // Returns when a reader has data or `timeout` has passed.
  void wait(Duration timeout) {
    eprosima::fastdds::dds::ConditionSeq active;
    wait_set_.wait(active, dds::to_dds_duration(timeout));
  }

  // Moves what every reader holds into `pending`, each sample's reception time moved onto the
  // recording's timeline (a sample without one counts as received now).
  // The clock is read after each take, so that every sample was received before it: one
  // received between an earlier reading and the take, across a step back of the wall clock,
  // looked an hour old (placed 10 s back: a clock step in the file). Returns the last reading.
  LogTimeline::Now take_into(Pending& pending, const LogTimeline& timeline) {
    LogTimeline::Now now = timeline.now();
    for (std::size_t i = 0; i < readers_.size(); ++i) {
      taken_.clear();
      readers_[i]->take(taken_);
      now = timeline.now();
      for (auto& sample : taken_) {
        // A gateway that stopped or was lost: its valves' last samples stay the recording's word.
        if (sample.writers_gone) continue;
        sample.received_ns = LogTimeline::place(sample.received_ns, now);
        pending.emplace(sample.received_ns, std::pair{i, std::move(sample)});
      }
    }
    return now;
  }

 private:
  TopicReaders() = default;

  std::vector<const TopicType*> types_;
  std::vector<std::unique_ptr<recording::TopicReader>> readers_;
  eprosima::fastdds::dds::WaitSet wait_set_;
  std::vector<TakenSample> taken_;  // kept between takes for its capacity
};

// One MCAP file of the recording with a channel per subscribed topic.
// The recorder's participant and its readers; made afresh when it joins again.
struct Joined {
  std::unique_ptr<dds::Participant> participant;
  // Null when it could not be made. A stalled participant (docs/topics.md, "A participant that
  // stops") hears nothing more, and deleting it waits forever.
  std::unique_ptr<dds::EventWatchdog> watchdog;
  std::unique_ptr<TopicReaders> readers;  // declared after: destroyed first

  bool stalled() const { return watchdog && watchdog->stalled(); }
};

Result<Joined> join(const RecorderOptions& options, const std::vector<std::string>& topics) {
  Joined joined;
  auto participant = dds::Participant::create(
      {.domain = options.domain, .profile_file = options.profile_file, .name = "teejet-record"});
  if (!participant) return participant.error();
  joined.participant = std::move(*participant);
  auto watchdog = dds::EventWatchdog::create(*joined.participant, {});
  if (watchdog) {
    joined.watchdog = std::move(*watchdog);
  } else {
    std::cerr << "teejet-record: warning: " << watchdog.error().reason << '\n';
  }
  auto readers = TopicReaders::open(*joined.participant, topics);
  if (!readers) return readers.error();
  joined.readers = std::move(*readers);
  return joined;
}

const Error kStalled{ErrorCode::kStalled,
                     "Fast DDS's event thread has run no timer for 30 s (a deadlock inside Fast "
                     "DDS, docs/topics.md, \"A participant that stops\"): the recording ends "
                     "here, finished, with what was taken before"};

// A recorder may wait long for its gateway: over TCP it joins again (dds::TcpRejoin) at most
// this far apart.
constexpr Duration kLongestRejoinInterval = 64s;

class RecordingFile {
 public:
  // Channels (and their schemas) are added with their first message: a topic nobody publishes
  // costs nothing, and each schema carries the whole IDL text.
  static Result<std::unique_ptr<RecordingFile>> open(const std::string& path,
                                                     const RecorderOptions& options) {
    auto sink = mcap::open_file_sink(path);
    if (!sink) return sink.error();
    auto writer =
        mcap::Writer::create(std::move(*sink), {.compression = options.compression,
                                                .chunk_size = options.chunk_size,
                                                .library = "teejet-record " TEEJET_VERSION});
    if (!writer) return writer.error();
    return std::unique_ptr<RecordingFile>(new RecordingFile(path, std::move(*writer)));
  }

  Status write(std::size_t topic, const TopicType& type, bool disposed, std::uint64_t log_time,
               std::uint64_t publish_time, std::span<const std::uint8_t> payload) {
    auto channel = channels_.find({topic, disposed});
    if (channel == channels_.end()) {
      auto added = add_channel(type, disposed);
      if (!added) return added.error();
      channel = channels_.emplace(std::pair{topic, disposed}, *added).first;
    }
    return writer_->write(channel->second, ++sequences_[channel->second], log_time, publish_time,
                          payload);
  }

  Status flush() { return writer_->flush(); }
  Status finish() { return writer_->finish(); }
  std::uint64_t bytes() const { return writer_->bytes_written(); }
  const std::string& path() const { return path_; }

 private:
  RecordingFile(std::string path, std::unique_ptr<mcap::Writer> writer)
      : path_(std::move(path)), writer_(std::move(writer)) {}

  Result<std::uint16_t> add_channel(const TopicType& type, bool disposed) {
    auto schema = schemas_.find(type.type_name);
    if (schema == schemas_.end()) {
      const auto idl = recording::valve_idl();
      auto added =
          writer_->add_schema(type.type_name, recording::kSchemaEncoding,
                              {reinterpret_cast<const std::uint8_t*>(idl.data()), idl.size()});
      if (!added) return added.error();
      schema = schemas_.emplace(type.type_name, *added).first;
    }
    std::map<std::string, std::string> metadata{{recording::kDdsTopicKey, type.topic}};
    std::string topic = type.topic;
    if (disposed) {
      topic += recording::kDisposedSuffix;
      metadata[recording::kInstanceStateKey] = recording::kDisposed;
    }
    return writer_->add_channel(schema->second, topic, recording::kMessageEncoding, metadata);
  }

  std::string path_;
  std::unique_ptr<mcap::Writer> writer_;
  std::map<std::string, std::uint16_t> schemas_;
  std::map<std::pair<std::size_t, bool>, std::uint16_t> channels_;
  std::map<std::uint16_t, std::uint32_t> sequences_;
};

class CandumpFile {
 public:
  static Result<std::unique_ptr<CandumpFile>> open(const std::string& path) {
    auto file = std::unique_ptr<CandumpFile>(new CandumpFile(path));
    if (!file->out_) {
      return Error{ErrorCode::kSystem, "cannot create '" + path + "': " + std::strerror(errno)};
    }
    return file;
  }
  // False for a sample that has no candump form (more than 8 bytes, a bad interface name).
  bool write(std::span<const std::uint8_t> payload) {
    const auto sample = bus_frame::deserialize(payload);
    if (!sample) return false;
    const auto line = bus_frame::to_candump_line(*sample);
    if (line) out_ << *line << '\n';
    return line.ok();
  }
  Status flush() {
    out_.flush();
    if (!out_) return Error{ErrorCode::kSystem, "cannot write '" + path_ + "'"};
    return {};
  }

 private:
  explicit CandumpFile(const std::string& path) : path_(path), out_(path) {}
  std::string path_;
  std::ofstream out_;
};

class Recording {
 public:
  Recording(const RecorderOptions& options, std::vector<const TopicType*> types,
            const LogTimeline& timeline)
      : options_(options), types_(std::move(types)), timeline_(timeline) {}

  Status start() {
    if (!options_.candump_path.empty()) {
      auto candump = CandumpFile::open(options_.candump_path);
      if (!candump) return candump.error();
      candump_ = std::move(*candump);
    }
    return open_next();
  }

  Status write(std::size_t topic, TakenSample& sample) {
    const TopicType& type = *types_[topic];
    const std::uint64_t log_time = sample.received_ns;
    const std::uint64_t publish_time = sample.source_ns != 0 ? sample.source_ns : log_time;
    // Its last sample names a disposed instance; a split file starts with the last of each.
    if (!last_samples_.admit(topic, type, sample)) {
      ++progress_.unknown_disposals;
      return {};
    }
    if (auto written =
            file_->write(topic, type, sample.disposed, log_time, publish_time, sample.payload);
        !written) {
      return written;
    }
    if (candump_ && !sample.disposed && type.topic == dds::topics::kBusFrame &&
        !candump_->write(sample.payload)) {
      ++progress_.frames_without_candump_line;
    }
    auto& tally =
        progress_.topics[sample.disposed ? type.topic + std::string(recording::kDisposedSuffix)
                                         : type.topic];
    ++tally.messages;
    tally.bytes += sample.payload.size();
    ++progress_.messages;
    ++messages_in_file_;
    // Never a file of nothing but schemas, however small --max-size is.
    if (options_.max_size != 0 && file_->bytes() >= options_.max_size && messages_in_file_ > 0) {
      return split();
    }
    return {};
  }

  Status flush() {
    if (candump_) {
      if (auto flushed = candump_->flush(); !flushed) return flushed;
    }
    return file_->flush();
  }

  Status finish() {
    Status finished = file_ ? file_->finish() : Status{};
    if (candump_) {
      if (auto flushed = candump_->flush(); !flushed && finished) finished = flushed;
    }
    if (file_) closed_bytes_ += file_->bytes();
    file_.reset();
    return finished;
  }

  void joined_again() { ++progress_.rejoins; }

  const Progress& progress(Duration elapsed) {
    progress_.elapsed = elapsed;
    progress_.file_bytes = closed_bytes_ + (file_ ? file_->bytes() : 0);
    return progress_;
  }

 private:
  // A new file starts with the last sample of every instance, so that it stands alone: its
  // log time is the split, its publish time the sample's own.
  Status split() {
    if (auto finished = file_->finish(); !finished) return finished;
    closed_bytes_ += file_->bytes();
    if (auto opened = open_next(); !opened) return opened;
    const std::uint64_t now = timeline_.now().timeline;
    messages_in_file_ = 0;
    for (const auto& [key, last] : last_samples_.held()) {
      if (auto written =
              file_->write(key.first, *types_[key.first], false, now, last.source_ns, last.payload);
          !written) {
        return written;
      }
    }
    return {};
  }

  Status open_next() {
    const std::string path =
        options_.max_size == 0 ? options_.output : split_file_name(options_.output, file_index_++);
    auto file = RecordingFile::open(path, options_);
    if (!file) return file.error();
    file_ = std::move(*file);
    progress_.files.push_back(path);
    return {};
  }

  const RecorderOptions& options_;
  const std::vector<const TopicType*> types_;  // by topic index
  const LogTimeline& timeline_;
  std::unique_ptr<RecordingFile> file_;
  std::unique_ptr<CandumpFile> candump_;
  int file_index_ = 0;
  std::uint64_t messages_in_file_ = 0;  // not counting the state a split file starts with
  std::uint64_t closed_bytes_ = 0;
  recording::LatestSamples last_samples_;
  Progress progress_;
};

// Writes the pending samples received up to `up_to`, in reception order, until one fails.
Status write_pending(Recording& recording, Pending& pending, std::uint64_t up_to) {
  while (!pending.empty() && pending.begin()->first <= up_to) {
    auto [topic, sample] = std::move(pending.begin()->second);
    pending.erase(pending.begin());
    if (auto written = recording.write(topic, sample); !written) return written;
  }
  return {};
}

// Takes, writes, flushes every flush_period and reports every kReportPeriod until `stop` is set,
// the duration has passed or a write fails, whose reason it returns. What is still pending then
// is the caller's.
Status record_until_stopped(Joined& joined, const std::vector<std::string>& topics,
                            Recording& recording, Pending& pending, const RecorderOptions& options,
                            const std::atomic<bool>& stop,
                            const std::function<void(const Progress&)>& report, SteadyTime start,
                            const Clock& clock, const LogTimeline& timeline) {
  dds::TcpRejoin rejoin(dds::TcpRejoin::kFirst, kLongestRejoinInterval);
  rejoin.joined(clock.steady());
  // Without --duration, the end is the stop flag alone.
  const SteadyTime end = options.duration ? start + *options.duration : SteadyTime::max();
  SteadyTime next_flush = start + options.flush_period;
  SteadyTime next_report = start + kReportPeriod;
  while (!stop.load()) {
    SteadyTime now = clock.steady();
    if (now >= end) break;
    if (joined.stalled()) return kStalled;
    joined.readers->wait(std::min({end, now + kLongestWait, next_flush, next_report}) - now);
    const LogTimeline::Now taken_at = joined.readers->take_into(pending, timeline);
    if (auto written = write_pending(recording, pending, taken_at.timeline - kReorderWindowNs);
        !written) {
      return written;
    }
    now = clock.steady();
    if (joined.stalled()) return kStalled;
    if (rejoin.replace(*joined.participant, now)) {
      // The old participant goes first: a new one that met it leaving would be in the very
      // situation that stalls it. What its readers held is pending already.
      joined.readers.reset();
      joined.watchdog.reset();
      joined.participant.reset();
      auto again = join(options, topics);
      if (!again) return again.error();
      joined = std::move(*again);
      rejoin.joined(now);
      recording.joined_again();
      if (report) report(recording.progress(now - start));
    }
    if (now >= next_flush) {
      if (auto flushed = recording.flush(); !flushed) return flushed;
      next_flush = now + options.flush_period;
    }
    if (now >= next_report) {
      if (report) report(recording.progress(now - start));
      next_report = now + kReportPeriod;
    }
  }
  return {};
}

}  // namespace

Result<std::vector<std::string>> select_topics(const std::vector<std::string>& globs) {
  std::vector<std::string> selected;
  for (const auto& glob : globs) {
    const bool any = std::any_of(
        recording::topic_types().begin(), recording::topic_types().end(),
        [&](const TopicType& type) { return recording::topic_matches(glob, type.topic); });
    if (!any) {
      std::string known;
      for (const auto& type : recording::topic_types()) known += "\n  " + type.topic;
      return Error{ErrorCode::kInvalidValue,
                   "--topic '" + glob + "' matches none of the teejet topics:" + known};
    }
  }
  for (const auto& type : recording::topic_types()) {
    const bool wanted =
        globs.empty() || std::any_of(globs.begin(), globs.end(), [&](const std::string& glob) {
          return recording::topic_matches(glob, type.topic);
        });
    if (wanted) selected.push_back(type.topic);
  }
  return selected;
}

std::string split_file_name(const std::string& output, int index) {
  const auto slash = output.find_last_of('/');
  const auto dot = output.find_last_of('.');
  const bool has_extension =
      dot != std::string::npos && (slash == std::string::npos || dot > slash);
  char number[16];
  std::snprintf(number, sizeof number, "_%03d", index);
  return has_extension ? output.substr(0, dot) + number + output.substr(dot) : output + number;
}

Result<Progress> record(const RecorderOptions& options, const std::atomic<bool>& stop,
                        const std::function<void(const Progress&)>& report,
                        const std::function<void()>& on_started) {
  auto selected = select_topics(options.topics);
  if (!selected) return selected.error();
  const auto clock = system_clock();
  auto joined = join(options, *selected);
  if (!joined) return joined.error();

  const LogTimeline timeline(*clock);
  Recording recording(options, joined->readers->types(), timeline);
  if (auto started = recording.start(); !started) {
    (void)recording.finish();  // the reason to report is the first one
    return started.error();
  }
  if (on_started) on_started();

  const SteadyTime start = clock->steady();
  Pending pending;
  Status recorded = record_until_stopped(*joined, *selected, recording, pending, options, stop,
                                         report, start, *clock, timeline);
  const bool stalled = !recorded && recorded.error().code == ErrorCode::kStalled;
  // What the readers still hold (a take waits for no timer), then everything taken.
  if (joined->readers) joined->readers->take_into(pending, timeline);
  if (recorded || stalled) {
    if (auto written = write_pending(recording, pending, UINT64_MAX); !written && recorded) {
      recorded = written;
    }
  }
  if (stalled) {
    // Left as they are: deleting them would wait for the stuck thread. The caller ends the
    // process (kStalled).
    (void)joined->readers.release();
    (void)joined->watchdog.release();
    (void)joined->participant.release();
  }
  // Readers first: nothing arrives while the file is closed. The file is finished before the
  // participant goes: a deletion that never ends (docs/topics.md, "A participant that stops")
  // leaves a whole file.
  joined->readers.reset();
  joined->watchdog.reset();
  const Status finished = recording.finish();
  joined->participant.reset();
  const Progress& progress = recording.progress(clock->steady() - start);
  if (report) report(progress);
  if (!recorded) return recorded.error();
  if (!finished) return finished.error();
  return progress;
}

}  // namespace teejet::record
