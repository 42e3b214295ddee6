// Every valve's presence in one message, one row per valve, for the Table panel:
// teejet/valve/presence carries one instance per valve on one topic, and a Table of the topic
// would show only the valve that spoke last.
//
// Foxglove starts the script anew at every seek; a valve's row comes back with its next
// presence sample (every I'm Here, about once a second).

import { Input } from "./types";

export const inputs = ["teejet/valve/presence"];
export const output = "/studio_script/teejet_valve_presence";

type ValvePresenceRow = {
  // "TJV" and the serial, as valvectl and the dashboard name valves
  valve: string;
  online: boolean;
  // the gateway that owns the valve's bus
  gateway: string;
  // its place in that gateway's layout; empty: in no place
  location: string;
  // current CAN source address, as the docs write it: 0xD8 .. 0xF7
  address: string;
  // the valve runs its boot loader, not the application
  boot_mode: boolean;
  // the number that the layout's variables (valve_a ... valve_d) take
  serial: number;
};

type ValvePresenceTable = {
  valve_count: number;
  online_count: number;
  valves: ValvePresenceRow[];
};

const rows = new Map<number, ValvePresenceRow>();

// TJV%06u, as the gateway's codec formats a serial (24 bits: up to 8 digits).
function valveName(serial: number): string {
  return `TJV${String(serial).padStart(6, "0")}`;
}

function hexAddress(address: number): string {
  return `0x${address.toString(16).toUpperCase().padStart(2, "0")}`;
}

export default function script(event: Input<"teejet/valve/presence">): ValvePresenceTable {
  const message = event.message;
  const serial = Number(message.serial);
  rows.set(serial, {
    valve: valveName(serial),
    online: Boolean(message.online),
    gateway: String(message.gateway),
    location: String(message.location),
    address: hexAddress(Number(message.address)),
    boot_mode: Boolean(message.boot_mode),
    serial,
  });

  const valves = [...rows.keys()].sort((a, b) => a - b).map((s) => rows.get(s) as ValvePresenceRow);
  return {
    valve_count: valves.length,
    online_count: valves.filter((row) => row.online).length,
    valves,
  };
}
