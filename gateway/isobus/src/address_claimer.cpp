#include "teejet/isobus/address_claimer.hpp"

#include <cstdio>

#include "teejet/codec/can_id.hpp"
#include "teejet/codec/codec.hpp"

namespace teejet::isobus {
namespace {

std::string hex_address(std::uint8_t address) { return codec::format_address(address); }

}  // namespace

Name ClaimConfig::default_name() {
  Name name;
  name.function = 128;
  name.device_class = 4;
  name.industry_group = 2;
  return name;
}

const char* to_string(ClaimState state) {
  switch (state) {
    case ClaimState::kOff:
      return "off";
    case ClaimState::kClaiming:
      return "claiming";
    case ClaimState::kClaimed:
      return "claimed";
    case ClaimState::kYielded:
      return "yielded";
  }
  return "unknown";
}

AddressClaimer::AddressClaimer(ClaimConfig config)
    : config_(std::move(config)),
      state_(config_.claim ? ClaimState::kClaiming : ClaimState::kOff) {}

std::string AddressClaimer::address_text() const { return hex_address(config_.address); }

ClaimReaction AddressClaimer::claim(SteadyTime now) {
  ClaimReaction reaction;
  if (!config_.claim) return reaction;
  reaction.send.push_back(request_for_address_claimed(kGlobalAddress, kNullAddress));
  send_claim(now, reaction);
  reaction.notices.push_back(
      {false, "claiming address " + address_text() + " as NAME " + to_text(config_.name)});
  return reaction;
}

void AddressClaimer::send_claim(SteadyTime now, ClaimReaction& reaction) {
  reaction.send.push_back(address_claimed(config_.name, config_.address));
  ++counters_.claims_sent;
  reaction.claim_sent = true;
  state_ = ClaimState::kClaiming;
  holder_.reset();
  neighbours_[config_.address].reset();  // a contender that lost, or a holder gone silent
  next_probe_.reset();
  probe_unanswered_at_.reset();
  wait_ends_ = now + config_.wait_after_claim;
}

void AddressClaimer::wait_from(SteadyTime sent) {
  if (state_ == ClaimState::kClaiming) wait_ends_ = sent + config_.wait_after_claim;
}

ClaimReaction AddressClaimer::on_frame(const codec::CanFrame& frame, Timestamp received,
                                       SteadyTime now) {
  ClaimReaction reaction;
  const NetworkFrame meaning = classify(frame);
  if (const auto* claimed = std::get_if<AddressClaim>(&meaning)) {
    on_claim(*claimed, received, now, reaction);
  } else if (const auto* request = std::get_if<ClaimRequest>(&meaning)) {
    on_request(*request, received, reaction);
  } else if (const auto source = std::get<OtherFrame>(meaning).source) {
    if (neighbours_[*source]) neighbours_[*source]->last_seen = received;
    // The holder's own traffic once we yielded; anyone else's is a second ECU at our address.
    if (*source == config_.address && state_ != ClaimState::kYielded) {
      ++counters_.address_violations;
      char id[16];
      std::snprintf(id, sizeof id, "0x%08X", frame.id);
      if (config_.claim) {
        reaction.notices.push_back(
            {true, "address violation: frame " + std::string(id) + " from " + address_text() +
                       " was not sent by this gateway; claiming " + address_text() + " again"});
        reaction.send.push_back(address_claimed(config_.name, config_.address));
        ++counters_.claims_sent;
      } else {
        reaction.notices.push_back({true, "frame " + std::string(id) + " from " + address_text() +
                                              " was not sent by this gateway: another ECU uses "
                                              "its address (isobus.claim is off)"});
      }
    }
  }
  return reaction;
}

void AddressClaimer::forget_name(const Name& name) {
  for (auto& neighbour : neighbours_) {
    if (neighbour && neighbour->name == name) neighbour.reset();
  }
}

void AddressClaimer::on_claim(const AddressClaim& claim, Timestamp received, SteadyTime now,
                              ClaimReaction& reaction) {
  // A NAME claims one address at a time: a new claim (or Cannot Claim) moves it.
  forget_name(claim.name);
  if (claim.source == kNullAddress) {
    if (state_ == ClaimState::kYielded && holder_ == claim.name) {
      reaction.notices.push_back({false, "NAME " + to_text(claim.name) + " that held " +
                                             address_text() +
                                             " cannot claim any more: taking it back"});
      send_claim(now, reaction);
    }
    return;
  }
  if (claim.source > kNullAddress) return;  // 0xFF is no source
  neighbours_[claim.source] = Neighbour{claim.source, claim.name, received};
  if (codec::is_valve_address(claim.source)) {
    ++counters_.claims_in_valve_range;
    reaction.notices.push_back(
        {true, "an ECU (NAME " + to_text(claim.name) + ") claimed " + hex_address(claim.source) +
                   ", an address valves pick for themselves: valve traffic from it is ignored "
                   "while it holds it"});
  }
  if (claim.source != config_.address) {
    // The holder moved elsewhere: our address is free.
    if (state_ == ClaimState::kYielded && holder_ == claim.name) {
      reaction.notices.push_back({false, "NAME " + to_text(claim.name) + " moved from " +
                                             address_text() + " to " + hex_address(claim.source) +
                                             ": taking " + address_text() + " back"});
      send_claim(now, reaction);
    }
    return;
  }
  if (state_ == ClaimState::kYielded) probe_unanswered_at_.reset();  // the holder answered
  if (!config_.claim) {
    reaction.notices.push_back({true, "NAME " + to_text(claim.name) + " claimed " + address_text() +
                                          ", this gateway's address (isobus.claim is off)"});
    return;
  }
  if (claim.name == config_.name) {
    ++counters_.address_violations;
    reaction.notices.push_back({true, "another ECU claimed " + address_text() +
                                          " with this gateway's own NAME " + to_text(claim.name) +
                                          ": two gateways configured alike on one bus?"});
    return;
  }
  if (wins_over(config_.name, claim.name)) {
    ++counters_.contentions_won;
    neighbours_[config_.address].reset();  // it must give the address up
    reaction.notices.push_back({true, "NAME " + to_text(claim.name) + " claimed " + address_text() +
                                          "; this gateway's NAME " + to_text(config_.name) +
                                          " has the higher priority and claims it again"});
    if (state_ == ClaimState::kYielded) {
      send_claim(now, reaction);  // the holder we yielded to is gone and this one loses
    } else {
      reaction.send.push_back(address_claimed(config_.name, config_.address));
      ++counters_.claims_sent;
    }
    return;
  }
  if (state_ == ClaimState::kYielded) {
    holder_ = claim.name;
    return;
  }
  ++counters_.contentions_lost;
  state_ = ClaimState::kYielded;
  holder_ = claim.name;
  next_probe_ = now + config_.probe_period;
  probe_unanswered_at_.reset();
  reaction.send.push_back(cannot_claim_address(config_.name));
  reaction.notices.push_back(
      {true, "gave up address " + address_text() + " to NAME " + to_text(claim.name) +
                 " (higher priority than this gateway's " + to_text(config_.name) +
                 "): sending nothing, refusing every command until it is free again"});
}

void AddressClaimer::on_request(const ClaimRequest& request, Timestamp received,
                                ClaimReaction& reaction) {
  if (neighbours_[request.source]) neighbours_[request.source]->last_seen = received;
  if (!config_.claim) return;
  if (request.destination != kGlobalAddress && request.destination != config_.address) return;
  if (state_ == ClaimState::kYielded) {
    // Asked to the address: the holder answers; asked to all: say we are here without one.
    if (request.destination == kGlobalAddress) {
      reaction.send.push_back(cannot_claim_address(config_.name));
    }
    return;
  }
  reaction.send.push_back(address_claimed(config_.name, config_.address));
  ++counters_.claims_sent;
}

ClaimReaction AddressClaimer::tick(SteadyTime now) {
  ClaimReaction reaction;
  if (state_ == ClaimState::kClaiming && now >= wait_ends_) {
    state_ = ClaimState::kClaimed;
    reaction.became_claimed = true;
    reaction.notices.push_back(
        {false, "holds address " + address_text() + " as NAME " + to_text(config_.name)});
  }
  if (state_ != ClaimState::kYielded) return reaction;
  if (probe_unanswered_at_ && now >= *probe_unanswered_at_) {
    reaction.notices.push_back({false, "NAME " + (holder_ ? to_text(*holder_) : std::string("?")) +
                                           " no longer answers for " + address_text() +
                                           ": taking it back"});
    send_claim(now, reaction);
    return reaction;
  }
  if (next_probe_ && now >= *next_probe_) {
    reaction.send.push_back(request_for_address_claimed(config_.address, kNullAddress));
    probe_unanswered_at_ = now + config_.probe_timeout;
    next_probe_ = now + config_.probe_period;
  }
  return reaction;
}

std::optional<SteadyTime> AddressClaimer::next_deadline() const {
  if (state_ == ClaimState::kClaiming) {
    if (wait_ends_ == SteadyTime::max()) return std::nullopt;  // claim() not called yet
    return wait_ends_;
  }
  if (state_ != ClaimState::kYielded) return std::nullopt;
  std::optional<SteadyTime> next = next_probe_;
  if (probe_unanswered_at_ && (!next || *probe_unanswered_at_ < *next)) {
    next = probe_unanswered_at_;
  }
  return next;
}

std::optional<std::string> AddressClaimer::refusal() const {
  switch (state_) {
    case ClaimState::kOff:
    case ClaimState::kClaimed:
      return std::nullopt;
    case ClaimState::kClaiming:
      return "the gateway is claiming its address " + address_text() +
             " (ISO 11783-5: nothing else is sent for " +
             std::to_string(
                 std::chrono::duration_cast<std::chrono::milliseconds>(config_.wait_after_claim)
                     .count()) +
             " ms after a claim); send the command again";
    case ClaimState::kYielded:
      return "the gateway gave its address " + address_text() + " up to an ECU with NAME " +
             (holder_ ? to_text(*holder_) : std::string("?")) +
             " (higher priority): it sends nothing until the address is free (docs/isobus.md)";
  }
  return std::nullopt;
}

std::vector<Neighbour> AddressClaimer::neighbours() const {
  std::vector<Neighbour> found;
  for (const auto& neighbour : neighbours_) {
    if (neighbour) found.push_back(*neighbour);
  }
  return found;
}

}  // namespace teejet::isobus
