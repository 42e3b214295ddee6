#include "valve_view.hpp"

#include <cmath>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <vector>

#include "names.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::valvectl {

using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::SampleInfo;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

namespace {

// Floats on the wire carry 0.1 or 0.01 resolution; round so that 12.3f prints as 12.3.
double rounded(float value, double resolution) {
  return std::round(static_cast<double>(value) / resolution) * resolution;
}

std::string version_text(const SoftwareVersion& version) {
  return codec::format_version(
      codec::SoftwareVersion{version.major(), version.minor(), version.test()});
}

std::string rotation_text(Rotation rotation) {
  return rotation == ROTATION_CLOCKWISE ? "clockwise" : "counterclockwise";
}

}  // namespace

template <class PubSubType, class Sample>
ValveView::Reader ValveView::subscribe(dds::Participant& participant, const char* topic,
                                       std::function<void(const Sample&)> on_sample) {
  // No listener yet: the constructor attaches them once handlers_ is complete.
  Reader reader = participant.reader(participant.topic<PubSubType>(topic),
                                     dds::topics::state_reader_qos(), nullptr);
  handlers_.emplace(reader, [this, on_sample = std::move(on_sample)](Reader from) {
    // Take first, then lock: Fast DDS holds the reader's lock while it calls the listener, so
    // taking with mutex_ held would invert the lock order against a listener thread.
    std::vector<Sample> samples;
    Sample sample;
    SampleInfo info;
    while (from->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
      if (info.valid_data) samples.push_back(sample);
    }
    if (samples.empty()) return;
    std::lock_guard lock(mutex_);
    for (const Sample& taken : samples) on_sample(taken);
    changed_.notify_all();
  });
  return reader;
}

ValveView::ValveView(dds::Participant& participant) {
  subscribe<ValvePresencePubSubType, ValvePresence>(
      participant, dds::topics::kPresence,
      [this](const ValvePresence& sample) { table_.on_presence(sample); });
  gateway_status_reader_ = subscribe<GatewayStatusPubSubType, GatewayStatus>(
      participant, dds::topics::kGatewayStatus,
      [this](const GatewayStatus& sample) { table_.on_gateway_status(sample); });
  subscribe<ValvePositionPubSubType, ValvePosition>(
      participant, dds::topics::kPosition, [this](const ValvePosition& sample) {
        table_.on_position(sample.serial(), rounded(sample.degrees(), 0.1), sample.received_ns());
      });
  subscribe<ValveTemperaturePubSubType, ValveTemperature>(
      participant, dds::topics::kTemperature, [this](const ValveTemperature& sample) {
        table_.on_temperature(sample.serial(), sample.valve_c(), sample.sensor_c(),
                              sample.received_ns());
      });
  subscribe<ValveVoltagePubSubType, ValveVoltage>(
      participant, dds::topics::kVoltage, [this](const ValveVoltage& sample) {
        table_.on_voltage(sample.serial(), rounded(sample.volts(), 0.1), sample.received_ns());
      });
  subscribe<ValveVersionPubSubType, ValveVersion>(
      participant, dds::topics::kVersion, [this](const ValveVersion& sample) {
        table_.on_reply(sample.serial(), reply_name(TELEMETRY_VERSION),
                        {sample.received_ns(),
                         {{"application", version_text(sample.application())},
                          {"bootloader", version_text(sample.bootloader())}}});
      });
  subscribe<ValveCurrentPubSubType, ValveCurrent>(
      participant, dds::topics::kCurrent, [this](const ValveCurrent& sample) {
        table_.on_reply(sample.serial(), reply_name(TELEMETRY_CURRENT),
                        {sample.received_ns(),
                         {{"amps", rounded(sample.amps(), 0.01)},
                          {"last_running_amps", rounded(sample.last_running_amps(), 0.01)}}});
      });
  subscribe<ValveDegreesPerSecondPubSubType, ValveDegreesPerSecond>(
      participant, dds::topics::kDegreesPerSecond, [this](const ValveDegreesPerSecond& sample) {
        table_.on_reply(sample.serial(), reply_name(TELEMETRY_DEGREES_PER_SECOND),
                        {sample.received_ns(),
                         {{"dps", sample.dps()}, {"direction", to_string(sample.direction())}}});
      });
  subscribe<ValveSpeedDirectionPubSubType, ValveSpeedDirection>(
      participant, dds::topics::kSpeedDirection, [this](const ValveSpeedDirection& sample) {
        table_.on_reply(sample.serial(), reply_name(TELEMETRY_SPEED_DIRECTION),
                        {sample.received_ns(),
                         {{"speed_percent", sample.speed_percent()},
                          {"direction", to_string(sample.direction())},
                          {"opening_direction", rotation_text(sample.opening_direction())}}});
      });
  subscribe<ValveRunTimePubSubType, ValveRunTime>(
      participant, dds::topics::kRunTime, [this](const ValveRunTime& sample) {
        table_.on_reply(sample.serial(), reply_name(TELEMETRY_RUN_TIME),
                        {sample.received_ns(), {{"seconds", sample.seconds()}}});
      });
  subscribe<ValveCycleCountPubSubType, ValveCycleCount>(
      participant, dds::topics::kCycleCount, [this](const ValveCycleCount& sample) {
        table_.on_reply(sample.serial(), reply_name(TELEMETRY_CYCLE_COUNTS),
                        {sample.received_ns(), {{"count", sample.count()}}});
      });
  subscribe<ValveBaudRatePubSubType, ValveBaudRate>(
      participant, dds::topics::kBaudRate, [this](const ValveBaudRate& sample) {
        table_.on_reply(sample.serial(), kBaudRateReply,
                        {sample.received_ns(), {{"bit_rate", sample.bit_rate()}}});
      });

  // Errors are keyed by (serial, kind) and disposed on Clear Errors: they need the instance.
  Reader errors = participant.reader(participant.topic<ValveErrorPubSubType>(dds::topics::kError),
                                     dds::topics::state_reader_qos(), nullptr);
  handlers_.emplace(errors, [this](Reader from) { take_errors(from); });

  // handlers_ is complete and stays as it is: listeners may look it up from now on. Samples
  // that arrived before a reader had its listener are taken right after.
  for (const auto& [reader, handler] : handlers_) {
    reader->set_listener(this, eprosima::fastdds::dds::StatusMask::data_available());
  }
  for (const auto& [reader, handler] : handlers_) handler(reader);
}

ValveView::~ValveView() {
  // Delete the readers while this listener still exists: the participant outlives the view.
  for (const auto& [reader, handler] : handlers_) {
    reader->set_listener(nullptr);
    // Fast DDS 2.9 hands out the owning subscriber as const only.
    const_cast<eprosima::fastdds::dds::Subscriber*>(reader->get_subscriber())
        ->delete_datareader(reader);
  }
}

void ValveView::take_errors(Reader reader) {
  std::vector<std::pair<ValveError, SampleInfo>> taken;  // taken before locking, as above
  ValveError sample;
  SampleInfo info;
  while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
    taken.emplace_back(sample, info);
  }
  if (taken.empty()) return;
  std::lock_guard lock(mutex_);
  for (const auto& [error, error_info] : taken) {
    if (error_info.valid_data) {
      error_instances_[error_info.instance_handle] = {error.serial(), error.kind()};
      table_.on_error(error.serial(), error.kind());
    } else if (error_info.instance_state ==
               eprosima::fastdds::dds::NOT_ALIVE_DISPOSED_INSTANCE_STATE) {
      if (const auto it = error_instances_.find(error_info.instance_handle);
          it != error_instances_.end()) {
        table_.on_error_cleared(it->second.first, it->second.second);
      }
    }
  }
  changed_.notify_all();
}

void ValveView::on_data_available(DataReader* reader) {
  if (const auto it = handlers_.find(reader); it != handlers_.end()) it->second(reader);
}

ValveTable ValveView::snapshot() const {
  update_gateways_matched();
  std::lock_guard lock(mutex_);
  return table_;
}

void ValveView::update_gateways_matched() const {
  eprosima::fastdds::dds::SubscriptionMatchedStatus matched;
  if (gateway_status_reader_->get_subscription_matched_status(matched) != ReturnCode::RETCODE_OK) {
    return;
  }
  std::lock_guard lock(mutex_);
  table_.set_gateways_matched(static_cast<std::size_t>(matched.current_count));
}

bool ValveView::wait_until(const Condition& condition, Deadline until,
                           const std::atomic<bool>& interrupted) const {
  // Discovery changes (matched writers) notify nobody: look again at least this often.
  constexpr auto kRecheck = std::chrono::milliseconds(50);
  for (;;) {
    update_gateways_matched();
    std::unique_lock lock(mutex_);
    if (condition(table_)) return true;
    const auto now = std::chrono::steady_clock::now();
    if (interrupted || now >= until) return false;
    changed_.wait_for(lock, std::min<std::chrono::steady_clock::duration>(kRecheck, until - now));
  }
}

}  // namespace teejet::valvectl
