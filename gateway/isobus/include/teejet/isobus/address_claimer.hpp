#pragma once

// One controller's side of ISO 11783-5 / J1939-81 address claiming at a fixed address (the
// sheet fixes the valve controller at 0xD5): it claims, waits before it sends, answers
// requests, defends the address against a NAME of lower priority, gives it up to one of higher
// priority and takes it back when it is free, and keeps the table of the other ECUs that claimed
// addresses on the bus. Pure: frames and time in, frames to send and notices out; the caller
// owns the bus, the clocks and the lock. docs/isobus.md.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "teejet/codec/frame.hpp"
#include "teejet/core/time.hpp"
#include "teejet/isobus/name.hpp"

namespace teejet::isobus {

struct ClaimConfig {
  // Off: the controller claims nothing, answers nothing and may always send (a bus that
  // carries only valves); it still listens, keeping the neighbour table and its warnings.
  bool claim = true;
  Name name = default_name();
  std::uint8_t address = 0xD5;
  // J1939-81: an ECU at an address in 128-247 waits this long after its claim before it sends
  // anything else, so that a contender of higher priority is heard first.
  Duration wait_after_claim = std::chrono::milliseconds(250);
  // While the address is held by another ECU: how often it is asked whether it still is (a
  // Request for Address Claimed to the address, from the null address), and how long an answer
  // may take before the address counts as free (J1939-21's response timeout).
  Duration probe_period = std::chrono::seconds(5);
  Duration probe_timeout = std::chrono::milliseconds(1250);

  // Industry group 2 (agricultural and forestry), device class 4 (sprayers), function 128,
  // not arbitrary-address capable; identity number and manufacturer code 0 until configured.
  static Name default_name();
};

enum class ClaimState : std::uint8_t {
  kOff,       // claiming is off
  kClaiming,  // claimed, waiting wait_after_claim before sending (or the bus is down)
  kClaimed,   // holds its address
  kYielded,   // gave its address up to a NAME of higher priority
};
const char* to_string(ClaimState state);

// An ECU that claimed an address on the bus.
struct Neighbour {
  std::uint8_t address = 0;
  Name name;
  Timestamp last_seen{};  // its claim, or any later frame from its address
};

struct ClaimCounters {
  std::uint64_t claims_sent = 0;
  std::uint64_t contentions_won = 0;        // a lower-priority NAME claimed our address
  std::uint64_t contentions_lost = 0;       // a higher-priority one did: we yielded
  std::uint64_t address_violations = 0;     // frames from our address not from us, not claims
  std::uint64_t claims_in_valve_range = 0;  // by ECUs, at the addresses valves pick
};

// What one call asks of the caller.
struct ClaimReaction {
  std::vector<codec::CanFrame> send;  // in order, before anything else is sent
  // Lines for the log, each whole; warnings are things a person should look at.
  struct Notice {
    bool warning = false;
    std::string text;
  };
  std::vector<Notice> notices;
  bool became_claimed = false;  // the wait after the claim ended: sending may start
  // `send` holds our claim: the wait runs from when it went out (AddressClaimer::wait_from).
  bool claim_sent = false;
};

class AddressClaimer {
 public:
  explicit AddressClaimer(ClaimConfig config);

  // Claims at start, and again after the bus recovered (link up, bus-off restart, interface
  // re-created): a Request for Address Claimed to everyone from the null address, so that the
  // neighbours answer, then the claim.
  ClaimReaction claim(SteadyTime now);
  // A frame another ECU sent (own frames are never received back).
  ClaimReaction on_frame(const codec::CanFrame& frame, Timestamp received, SteadyTime now);
  // The claim of the last reaction went out at `sent`: the wait after it runs from there, not
  // from when it was decided (sending the request before it takes a while on a loaded bus).
  void wait_from(SteadyTime sent);
  // Whatever is due: the end of the wait after the claim, a probe of the holder.
  ClaimReaction tick(SteadyTime now);
  // When tick() next has something to do; nullopt: nothing.
  std::optional<SteadyTime> next_deadline() const;

  // Whether frames other than claiming may go out from our address now.
  bool may_send() const { return state_ == ClaimState::kOff || state_ == ClaimState::kClaimed; }
  // Why a command is not sent now, for its REJECTED status; nullopt when it may be.
  std::optional<std::string> refusal() const;

  ClaimState state() const { return state_; }
  const ClaimConfig& config() const { return config_; }
  // The NAME our address was given up to, while yielded.
  const std::optional<Name>& holder() const { return holder_; }
  std::vector<Neighbour> neighbours() const;  // by address
  // Whether an ECU (not a valve: valves never claim) holds `address`.
  bool claimed_by_neighbour(std::uint8_t address) const { return neighbours_[address].has_value(); }
  const ClaimCounters& counters() const { return counters_; }

 private:
  void on_claim(const AddressClaim& claim, Timestamp received, SteadyTime now,
                ClaimReaction& reaction);
  void on_request(const ClaimRequest& request, Timestamp received, ClaimReaction& reaction);
  void send_claim(SteadyTime now, ClaimReaction& reaction);
  void forget_name(const Name& name);
  std::string address_text() const;

  const ClaimConfig config_;
  ClaimState state_;
  std::optional<Name> holder_;
  SteadyTime wait_ends_ = SteadyTime::max();  // until claim(): not sending
  std::optional<SteadyTime> next_probe_;
  std::optional<SteadyTime> probe_unanswered_at_;
  std::array<std::optional<Neighbour>, 256> neighbours_{};
  ClaimCounters counters_;
};

}  // namespace teejet::isobus
