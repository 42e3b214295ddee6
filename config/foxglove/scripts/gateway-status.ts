// Every gateway's latest status in one message, one row per gateway, for the Table panel:
// teejet/gateway/status carries one instance per gateway (keyed by its name) on one topic.
//
// Each gateway publishes its status once a second, so after a seek every row is back within a
// second of playback. A gateway that died keeps its last row: age_s grows while others publish.

import { Input } from "./types";

export const inputs = ["teejet/gateway/status"];
export const output = "/studio_script/teejet_gateways";

type GatewayRow = {
  gateway: string;
  can_interface: string;
  // the BusState enumerator's name, e.g. BUS_ERROR_ACTIVE; the number itself when unknown
  bus_state: string;
  valves_online: number;
  valves_known: number;
  // uint64 counters as numbers: exact below 2^53 (at 2,600 frames a second, 100,000 years)
  frames_in: number;
  decode_errors: number;
  // the AddressClaimState enumerator's name, e.g. CLAIM_CLAIMED
  address_claim: string;
  // since this gateway's last status, at the newest status of any gateway
  age_s: number;
};

type GatewayTable = {
  gateway_count: number;
  gateways: GatewayRow[];
};

// In the order of idl/teejet/valve.idl: an enum arrives as its enumerator's number.
const BUS_STATES = [
  "BUS_ERROR_ACTIVE",
  "BUS_ERROR_WARNING",
  "BUS_ERROR_PASSIVE",
  "BUS_OFF",
  "BUS_DOWN",
];
const CLAIM_STATES = ["CLAIM_OFF", "CLAIM_CLAIMING", "CLAIM_CLAIMED", "CLAIM_YIELDED"];

type Latest = { row: GatewayRow; receivedS: number };

const latest = new Map<string, Latest>();
let newestS = 0;

function seconds(time: { sec: number; nsec: number }): number {
  return time.sec + time.nsec / 1e9;
}

function enumName(names: string[], value: number): string {
  return names[value] ?? String(value);
}

export default function script(event: Input<"teejet/gateway/status">): GatewayTable {
  const message = event.message;
  const receivedS = seconds(event.receiveTime);
  newestS = Math.max(newestS, receivedS);
  latest.set(String(message.gateway), {
    receivedS,
    row: {
      gateway: String(message.gateway),
      can_interface: String(message.can_interface),
      bus_state: enumName(BUS_STATES, Number(message.bus_state)),
      valves_online: Number(message.valves_online),
      valves_known: Number(message.valves_known),
      frames_in: Number(message.frames_in),
      decode_errors: Number(message.decode_errors),
      address_claim: enumName(CLAIM_STATES, Number(message.address_claim)),
      age_s: 0,
    },
  });

  const names = [...latest.keys()].sort();
  const gateways = names.map((name) => {
    const entry = latest.get(name) as Latest;
    return { ...entry.row, age_s: Math.round((newestS - entry.receivedS) * 1000) / 1000 };
  });
  return { gateway_count: gateways.length, gateways };
}
