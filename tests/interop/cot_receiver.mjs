// A TAK client's side of Cursor-on-Target, for tests/interop/cot_test.cc: joins a UDP
// multicast group on one interface, parses every datagram with @tak-ps/node-cot (the
// library TAK tools are written with), and writes one JSON line per event.
//   node cot_receiver.mjs GROUP PORT INTERFACE SECONDS OUT
import dgram from 'node:dgram';
import fs from 'node:fs';
import { CoTParser } from '@tak-ps/node-cot';

const [group, port, iface, seconds, out] = process.argv.slice(2);
const lines = [];
let failures = 0;
const socket = dgram.createSocket({ type: 'udp4', reuseAddr: true });
socket.on('message', (message) => {
  try {
    const cot = CoTParser.from_xml(message.toString('utf8'));
    const event = cot.raw.event;
    const detail = event.detail || {};
    lines.push(JSON.stringify({
      uid: event._attributes.uid,
      type: event._attributes.type,
      time: event._attributes.time,
      stale: event._attributes.stale,
      callsign: detail.contact ? detail.contact._attributes.callsign : null,
      remarks: detail.remarks ? detail.remarks._text : null,
      course: detail.track ? Number(detail.track._attributes.course) : null,
      lat: Number(event.point._attributes.lat),
      lon: Number(event.point._attributes.lon),
      hae: Number(event.point._attributes.hae),
      ce: Number(event.point._attributes.ce),
    }));
  } catch (e) {
    failures += 1;
    lines.push(JSON.stringify({ error: String(e), xml: message.toString('utf8') }));
  }
  fs.writeFileSync(out, lines.join('\n') + '\n');
});
socket.bind(Number(port), () => {
  socket.addMembership(group, iface);
  fs.writeFileSync(out + '.ready', 'listening\n');
});
setTimeout(() => {
  socket.close();
  process.exit(failures ? 1 : 0);
}, Number(seconds) * 1000);
