// Every valve's latest position in one message. Foxglove's Plot draws one series per message
// path, and teejet/valve/position carries one message per valve on one topic: a plain path would
// join all valves into one zigzag line. Here the valves become one array, which the Plot panel
// draws against its "index" x axis (one point per valve, redrawn at every sample) and the Table
// panel lists; its order is by serial, so a valve keeps its index in a recording and live.
//
// Foxglove runs this script on recorded and live data alike, and starts it anew at every seek:
// a valve then appears with its next sample (10 a second by default).

import { Input } from "./types";

export const inputs = ["teejet/valve/position"];
export const output = "/studio_script/teejet_valve_positions";

type ValvePositionRow = {
  // the valve's x in the Plot panel's index axis
  index: number;
  // "TJV" and the serial, as valvectl and the dashboard name valves
  valve: string;
  // the number that the layout's variables (valve_a ... valve_d) take
  serial: number;
  degrees: number;
  // since this valve's last sample, at the newest sample of any valve: a valve that went quiet
  // keeps its last position here, and this says how old it is
  age_s: number;
};

type ValvePositions = {
  valve_count: number;
  valves: ValvePositionRow[];
};

type Latest = { degrees: number; receivedS: number };

const latest = new Map<number, Latest>();
let newestS = 0;

function seconds(time: { sec: number; nsec: number }): number {
  return time.sec + time.nsec / 1e9;
}

// TJV%06u, as the gateway's codec formats a serial (24 bits: up to 8 digits).
function valveName(serial: number): string {
  return `TJV${String(serial).padStart(6, "0")}`;
}

export default function script(event: Input<"teejet/valve/position">): ValvePositions {
  const receivedS = seconds(event.receiveTime);
  // uint32 and float32 arrive as numbers; Number() keeps this right for a decoder that would
  // hand out bigints.
  latest.set(Number(event.message.serial), { degrees: Number(event.message.degrees), receivedS });
  newestS = Math.max(newestS, receivedS);

  const serials = [...latest.keys()].sort((a, b) => a - b);
  const valves = serials.map((serial, index) => {
    const last = latest.get(serial) as Latest;
    return {
      index,
      valve: valveName(serial),
      serial,
      degrees: last.degrees,
      age_s: Math.round((newestS - last.receivedS) * 1000) / 1000,
    };
  });
  return { valve_count: valves.length, valves };
}
