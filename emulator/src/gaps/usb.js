// USB, gaps 9-12 of rp2040js 1.4.1 (numbered as in index.js).
//
// The chip: a full-speed USB device controller whose host enumerates it, opens the CDC port
// (DTR), and takes or sends bulk packets as the bus and its program allow.
//
// 9-12. USB. rp2040js has a device-mode USB controller and a scripted host, `USBCDC`, which
//    enumerates a CDC ACM device (only with EP0's max packet size 64, which the firmware uses)
//    and then exchanges bytes. `UsbCdcHost` drives `USBCDC` and fills its gaps:
// 9. OUT arms before enumeration: `USBCDC` hands bytes to an OUT buffer only when the firmware
//    arms it after enumeration (`onEndpointRead` once the endpoint is known); rp2040-hal arms
//    its bulk OUT buffer at bus reset, before that, so host-to-device bytes never arrived.
//    `UsbCdcHost` keeps each OUT arm (endpoint, size) and completes it with the host's next
//    bytes when it has some (`endpointReadDone`). That is also USB's flow control, as on the
//    wire: a device that does not re-arm its buffer gets nothing more; the host waits (NAK).
// 10. The line state: `USBCDC` sends SET_CONTROL_LINE_STATE with recipient Device, which
//    usbd-serial (rightly: CDC PSTN 6.3.12 addresses it to the communication interface)
//    rejects, so the device never saw DTR. `UsbCdcHost` sends its own request, recipient
//    Interface, wIndex 0 (the communication interface), whenever the host opens (DTR and RTS
//    up) or closes (both down) its port, one control transfer at a time. And `USBCDC` sends
//    its next request the instant SET_ADDRESS's status stage reaches it; a real host leaves
//    the device the SetAddress() recovery interval, 2 ms (USB 2.0, 9.2.6.3). Without it, a
//    firmware whose interrupt had not handled the status stage yet (usb-device applies the
//    address then) saw the next SETUP first, applied the address after SET_CONFIGURATION and
//    fell back from Configured to Addressed: the port never opened (with the XIP cache model,
//    gap 13, the USB stack runs slower from flash). `UsbCdcHost` holds that request 2 ms.
// 11. IN timing: an IN buffer the firmware arms counts as taken at once (its buffer-status bit
//    is set on the spot, the data reaches the host 10 us later), whatever the host or the bus.
//    That flatters the firmware: it never waits for the bus and never meets a host that does
//    not read. `UsbCdcHost` takes each armed IN packet only while its host reads, on a
//    full-speed bus that carries at most 19 bulk packets of 64 bytes per 1 ms frame: every
//    bulk transaction, IN or OUT, whatever its length, holds the bus for 1/19 ms, one after
//    the other, and a packet completes (reaches the host, or the device's buffer) at the end
//    of its slot. A short packet takes the whole slot (on the wire it is shorter), so figures
//    err on the slow side. A host that stops reading leaves the IN buffer armed, as a real
//    host whose program and OS buffers are full does. A slow reader (`setReadInterval`)
//    takes one IN packet per interval at most, as a host whose OS buffers are full and whose
//    program reads a packet's worth at a time does: the next packet waits for the interval
//    from the last one taken, then for its bus slot.
// 12. Suspend and unplugging: on the chip SIE_STATUS.SUSPENDED is write-one-to-clear;
//    rp2040js does not clear it, so the suspend interrupt would fire for ever. Writing it now
//    clears it. Unplugging (`UsbCdcHost.unplug`) stops all traffic, and 3 ms later the device
//    sees the suspend an idle bus signals; replugging is a new host: a bus reset (10 ms, as
//    rp2040js's `resetDevice`) and a new enumeration. `USBCDC` can enumerate only once, so
//    each plug-in gets a fresh one.
//    Not modelled: resume signalling, VBUS (the firmware forces VBUS detect, as a Pico must),
//    EP0 traffic's share of the bus, errors and retries on the wire.

import { createSetupPacket, DataDirection, SetupRecipient, SetupType, USBCDC } from 'rp2040js';

// USB controller registers and DPRAM (RP2040 datasheet, 4.1.4).
const SIE_STATUS = 0x50;
const SIE_SUSPENDED = 1 << 4;
const EP0_IN_BUFFER_CONTROL = 0x80;
const BUF_CTRL_AVAILABLE = 1 << 10;
const BUF_CTRL_FULL = 1 << 15;
const BUF_CTRL_LEN_MASK = 0x3ff;
/** CDC PSTN SET_CONTROL_LINE_STATE; DTR is bit 0 of its value, RTS bit 1. */
const SET_CONTROL_LINE_STATE = 0x22;
const SET_LINE_CODING = 0x20;
const GET_DESCRIPTOR = 6;
const SET_ADDRESS = 5;
const DTR_AND_RTS = 0b11;
/** The communication interface of the firmware's CDC ACM function. */
const CDC_COMM_INTERFACE = 0;
/** Full speed: at most 19 bulk packets of 64 bytes per 1 ms frame (USB 2.0, table 5-10). */
export const BULK_PACKETS_PER_FRAME = 19;
const FRAME_NANOS = 1e6;
/** One bulk transaction's share of the bus, either direction (gap 11). */
export const BULK_PACKET_NANOS = FRAME_NANOS / BULK_PACKETS_PER_FRAME;
export const BULK_PACKET_BYTES = 64;
/** An idle bus for this long makes a device suspend (USB 2.0, 7.1.7.6). */
const SUSPEND_AFTER_NANOS = 3e6;
/** The SetAddress() recovery interval: no request before it has passed (USB 2.0, 9.2.6.3). */
export const SET_ADDRESS_RECOVERY_NANOS = 2e6;

/**
 * A USB host with a CDC ACM (serial) port on the emulated chip's USB controller: it
 * enumerates the firmware, opens and closes its port (DTR), sends bytes and receives what the
 * firmware sends, on a full-speed bus, and can stop reading, be unplugged and plugged in again
 * (gaps 9-12). `onData(bytes)` receives the device's bytes in order.
 */
export class UsbCdcHost {
  /**
   * @param {object} options
   * @param {boolean} [options.open] open the port (DTR) as soon as the device is configured,
   *   as a terminal program waiting for the port does (default true)
   * @param {(bytes: Uint8Array) => void} [options.onData]
   */
  constructor({ open = true, onData = () => {} } = {}) {
    this.wantOpen = open;
    this.onData = onData;
    this.plugged = true;
    /** The host's program reads (IN packets are taken). */
    this.reading = true;
    /** A slow reader: the least time from one IN packet taken to the next (0: the bus's pace). */
    this.readIntervalNanos = 0;
    /** When the last IN packet was taken. */
    this.lastInNanos = -Infinity;
    /** Bytes waiting to be sent, in order. */
    this.pending = [];
    this.pendingHead = 0;
    /** Times the device was configured (one per plug-in or chip reset). */
    this.enumerations = 0;
    /** Packets each way so far, and bytes. */
    this.inPackets = 0;
    this.outPackets = 0;
    this.inBytes = 0;
    this.outBytes = 0;
    /** Called with (bytes, nanos) when an OUT packet reaches the device's buffer. */
    this.onOutDelivered = null;
  }

  /** Puts the host on a fresh chip's USB port (at power-on, or after a chip reset). */
  attach(mcu) {
    this.mcu = mcu;
    this.usb = mcu.usbCtrl;
    this.clock = mcu.clock;
    this.busFreeNanos = 0;
    this.inAlarm = this.clock.createAlarm(() => this.inTaken());
    this.readAlarm = this.clock.createAlarm(() => this.readDue());
    this.outAlarm = this.clock.createAlarm(() => this.outDelivered());
    this.suspendAlarm = this.clock.createAlarm(() => this.suspendDevice());
    this.recoveryAlarm = this.clock.createAlarm(() => this.recovered());
    // Gap 12: SUSPENDED is write-one-to-clear.
    const usb = this.usb;
    const writeRegister = usb.writeUint32.bind(usb);
    usb.writeUint32 = (offset, value) => {
      writeRegister(offset, value);
      if (offset === SIE_STATUS && usb.rawWriteValue & SIE_SUSPENDED) {
        usb.sieStatus &= ~SIE_SUSPENDED;
        usb.sieStatusUpdated();
      }
    };
    // Gap 11: bulk IN buffers are taken by the host, not by the controller on its own.
    const dpramUpdated = usb.DPRAMUpdated.bind(usb);
    usb.DPRAMUpdated = (offset, value) => {
      if (!this.inBufferWrite(offset, value)) {
        dpramUpdated(offset, value);
      }
    };
    this.newBus();
    if (this.plugged) {
      this.plugIn(false);
    }
  }

  /** Nothing armed, nothing in flight: a chip just reset or a host just plugged in. */
  newBus() {
    this.outArms = new Map(); // endpoint -> size (gap 9)
    this.outPacket = null; // { endpoint, bytes } on the wire
    this.outAlarm.cancel();
    this.inArm = null; // { endpoint, offset } (gap 11)
    this.inScheduled = false;
    this.inAlarm.cancel();
    this.readAlarm.cancel();
    this.recoveryAlarm.cancel();
    this.afterRecovery = null;
    this.controlQueue = [];
    this.control = null;
    this.configured = false;
    this.portOpen = false;
  }

  /**
   * A fresh `USBCDC` enumerates the device. `reset`: the host resets the bus itself (a
   * replug); at power-on the firmware's enabling the controller does (rp2040js's
   * `onUSBEnabled`).
   */
  plugIn(reset) {
    // `any`: the fields used here (`initialized`, `outEndpoint`, `descriptors`,
    // `cdcSetControlLineState`) are private in rp2040js's types.
    const cdc = /** @type {any} */ (new USBCDC(this.usb));
    this.cdc = cdc;
    // Gap 10: the line state goes to the interface, when the host wants it.
    cdc.cdcSetControlLineState = () => {
      cdc.initialized = true;
    };
    cdc.onDeviceConnected = () => {
      this.configured = true;
      this.enumerations++;
      if (this.wantOpen) {
        this.setLineState(true);
      }
      this.nextControl();
      this.sendSome();
    };
    // Gap 9: keep OUT arms (the bulk OUT endpoint is armed before `USBCDC` knows it).
    cdc.usb.onEndpointRead = (endpoint, size) => {
      if (endpoint !== 0) {
        this.outArms.set(endpoint, size);
        this.sendSome();
      } else if (this.control?.out) {
        // The data stage of our control OUT request.
        this.usb.endpointReadDone(0, this.control.out);
        this.control.out = null;
      }
    };
    const endpointWrite = this.usb.onEndpointWrite;
    this.usb.onEndpointWrite = (endpoint, buffer) => {
      if (endpoint === 0 && this.control) {
        this.controlPacket(buffer); // ours, not `USBCDC`'s enumeration
        return;
      }
      if (endpoint === 0 && this.isSetAddress(this.mcu.usbDPRAM)) {
        // Gap 10: SET_ADDRESS's status stage: `USBCDC` would send its next request at once.
        this.afterRecovery = () => endpointWrite(endpoint, buffer);
        this.recoveryAlarm.schedule(SET_ADDRESS_RECOVERY_NANOS);
        return;
      }
      endpointWrite(endpoint, buffer);
    };
    if (reset) {
      this.usb.resetDevice();
    }
  }

  /** The setup packet at the start of DPRAM (the last one sent) is a SET_ADDRESS. */
  isSetAddress(dpram) {
    return dpram[0] === 0 && dpram[1] === SET_ADDRESS;
  }

  /** The SetAddress() recovery interval has passed: `USBCDC` goes on enumerating. */
  recovered() {
    const next = this.afterRecovery;
    this.afterRecovery = null;
    if (this.plugged) {
      next?.();
    }
  }

  // ---- the host's side: the port ----

  /** The device is configured and the host has its port open (DTR up). */
  get open() {
    return this.portOpen;
  }

  /** Opens the port (DTR and RTS up), as a terminal program does. */
  openPort() {
    this.wantOpen = true;
    if (this.configured && this.plugged) {
      this.setLineState(true);
    }
  }

  /** Closes the port (DTR and RTS down). */
  closePort() {
    this.wantOpen = false;
    if (this.configured && this.plugged) {
      this.setLineState(false);
    }
  }

  /** Queues bytes to send; they go as the device takes them, at most 64 to a packet. */
  send(bytes) {
    for (const byte of bytes) {
      this.pending.push(byte & 0xff);
    }
    this.sendSome();
  }

  /** Bytes queued by `send` that the device has not taken yet. */
  get unsent() {
    return this.pending.length - this.pendingHead;
  }

  /** Stops or resumes reading (a stopped host leaves the device's IN buffer full). */
  setReading(reading) {
    this.reading = reading;
    this.scheduleIn();
  }

  /**
   * Makes the host's program a slow reader: one IN packet taken per `ms` milliseconds at most
   * (0: as fast as the bus carries them).
   */
  setReadInterval(ms) {
    this.readIntervalNanos = ms * 1e6;
    this.scheduleIn();
  }

  /** Pulls the cable: all traffic stops; the device sees a suspend 3 ms later. */
  unplug() {
    if (!this.plugged) {
      return;
    }
    this.plugged = false;
    this.configured = false;
    this.portOpen = false;
    this.inAlarm.cancel();
    this.readAlarm.cancel();
    this.inScheduled = false;
    this.outAlarm.cancel();
    this.outPacket = null;
    this.pending = [];
    this.pendingHead = 0;
    this.suspendAlarm.schedule(SUSPEND_AFTER_NANOS);
  }

  /** Plugs the cable back in: a new host session (bus reset, enumeration, port per `open`). */
  replug({ open = true } = {}) {
    if (this.plugged) {
      return;
    }
    this.suspendAlarm.cancel();
    this.wantOpen = open;
    this.plugged = true;
    this.newBus();
    this.plugIn(true);
  }

  suspendDevice() {
    if (!this.plugged) {
      this.usb.sieStatus |= SIE_SUSPENDED;
      this.usb.sieStatusUpdated();
    }
  }

  // ---- control transfers (gap 10; one at a time, after enumeration) ----

  setLineState(open) {
    this.controlQueue.push({
      setup: {
        dataDirection: DataDirection.HostToDevice,
        type: SetupType.Class,
        recipient: SetupRecipient.Interface,
        bRequest: SET_CONTROL_LINE_STATE,
        wValue: open ? DTR_AND_RTS : 0,
        wIndex: CDC_COMM_INTERFACE,
        wLength: 0,
      },
      done: () => {
        this.portOpen = open;
        this.scheduleIn();
      },
    });
    this.nextControl();
  }

  /**
   * Sets the port's line coding (SET_LINE_CODING, as a terminal program does when opening a
   * serial port at `baud`, 8N1); calls `done()` when the device has acknowledged it.
   */
  setLineCoding(baud, done = () => {}) {
    const coding = new Uint8Array(7);
    new DataView(coding.buffer).setUint32(0, baud, true);
    coding[6] = 8; // 1 stop bit, no parity, 8 data bits
    this.controlQueue.push({
      setup: {
        dataDirection: DataDirection.HostToDevice,
        type: SetupType.Class,
        recipient: SetupRecipient.Interface,
        bRequest: SET_LINE_CODING,
        wValue: 0,
        wIndex: CDC_COMM_INTERFACE,
        wLength: coding.length,
      },
      out: coding,
      done,
    });
    this.nextControl();
  }

  /**
   * Reads a descriptor with GET_DESCRIPTOR (`type` 1 device, 3 string; `index`; `langId` for
   * strings) once the device is configured; calls `done(bytes)`.
   */
  readDescriptor(type, index, done, { langId = 0, length = 255 } = {}) {
    this.controlQueue.push({
      setup: {
        dataDirection: DataDirection.DeviceToHost,
        type: SetupType.Standard,
        recipient: SetupRecipient.Device,
        bRequest: GET_DESCRIPTOR,
        wValue: (type << 8) | index,
        wIndex: langId,
        wLength: length,
      },
      data: [],
      done,
    });
    this.nextControl();
  }

  nextControl() {
    if (this.control || this.controlQueue.length === 0 || !this.configured || !this.plugged) {
      return;
    }
    this.control = this.controlQueue.shift();
    this.usb.sendSetupPacket(createSetupPacket(this.control.setup));
  }

  /** A packet the device sent on endpoint 0 for our request: data, or the status stage. */
  controlPacket(buffer) {
    const control = this.control;
    if (control.data) {
      control.data.push(...buffer);
      // The data stage ends with a short packet or when the length asked for has come (the
      // status stage, an OUT ZLP, is not sent: usb-device takes the next SETUP all the same).
      if (buffer.length === BULK_PACKET_BYTES && control.data.length < control.setup.wLength) {
        return;
      }
    }
    this.control = null;
    control.done(control.data && Uint8Array.from(control.data));
    this.nextControl();
  }

  // ---- the bus (gap 11) ----

  /** Reserves the bus for one bulk transaction; returns when it ends. */
  busSlot() {
    const start = Math.max(this.clock.nanos, this.busFreeNanos);
    this.busFreeNanos = start + BULK_PACKET_NANOS;
    return this.busFreeNanos;
  }

  get trafficAllowed() {
    return this.plugged && this.configured && this.cdc?.outEndpoint > 0;
  }

  /** Sends the next packet if the device has an OUT buffer armed and bytes wait. */
  sendSome() {
    if (!this.trafficAllowed || this.outPacket || this.unsent === 0) {
      return;
    }
    const endpoint = this.cdc.outEndpoint;
    const size = this.outArms.get(endpoint);
    if (size === undefined) {
      return; // the device has not re-armed: it cannot take more, the host waits (NAK)
    }
    this.outArms.delete(endpoint);
    const count = Math.min(size, BULK_PACKET_BYTES, this.unsent);
    const bytes = Uint8Array.from(this.pending.slice(this.pendingHead, this.pendingHead + count));
    this.pendingHead += count;
    if (this.pendingHead === this.pending.length) {
      this.pending = [];
      this.pendingHead = 0;
    }
    this.outPacket = { endpoint, bytes };
    this.outAlarm.schedule(this.busSlot() - this.clock.nanos);
  }

  /** The OUT packet's slot ended: it is in the device's buffer (buffer-status bit set). */
  outDelivered() {
    const { endpoint, bytes } = this.outPacket;
    this.outPacket = null;
    this.outPackets++;
    this.outBytes += bytes.length;
    this.usb.finishRead(endpoint, bytes);
    this.onOutDelivered?.(bytes, this.clock.nanos);
    this.sendSome();
  }

  /**
   * A write to an IN endpoint's buffer control (endpoints 1..15; endpoint 0 is `USBCDC`'s):
   * arming it (AVAILABLE) waits for the host; a write that clears AVAILABLE (the firmware
   * resetting its endpoints) withdraws the arm. Returns whether this was such a write.
   */
  inBufferWrite(offset, value) {
    const index = (offset - EP0_IN_BUFFER_CONTROL) >> 3;
    const isIn =
      offset >= EP0_IN_BUFFER_CONTROL && offset < EP0_IN_BUFFER_CONTROL + 16 * 8 && !(offset & 4);
    if (!isIn || index === 0) {
      return false;
    }
    this.inAlarm.cancel();
    this.readAlarm.cancel();
    this.inScheduled = false;
    this.inArm = value & BUF_CTRL_AVAILABLE ? { endpoint: index, offset } : null;
    this.scheduleIn();
    return true;
  }

  /** Has the host take the armed IN packet in the next free bus slot, if it reads. */
  scheduleIn() {
    const takes = this.reading && this.portOpen && this.trafficAllowed;
    if (!this.inArm || this.inScheduled || !takes) {
      return;
    }
    this.inScheduled = true;
    const untilRead = this.lastInNanos + this.readIntervalNanos - this.clock.nanos;
    if (untilRead > 0) {
      this.readAlarm.schedule(untilRead); // a slow reader: the bus slot is taken then
      return;
    }
    this.inAlarm.schedule(this.busSlot() - this.clock.nanos);
  }

  /** A slow reader's interval has passed: the armed packet takes the next bus slot. */
  readDue() {
    this.inScheduled = false;
    this.scheduleIn();
  }

  inTaken() {
    this.inScheduled = false;
    const arm = this.inArm;
    if (!arm || !this.reading || !this.plugged) {
      return;
    }
    const view = this.mcu.usbDPRAMView;
    const control = view.getUint32(arm.offset, true);
    const length = control & BUF_CTRL_LEN_MASK;
    const start = this.usb.getEndpointBufferOffset(arm.endpoint, false);
    const data = this.mcu.usbDPRAM.slice(start, start + length);
    view.setUint32(arm.offset, control & ~(BUF_CTRL_AVAILABLE | BUF_CTRL_FULL), true);
    this.inArm = null;
    this.lastInNanos = this.clock.nanos;
    this.inPackets++;
    this.inBytes += length;
    this.usb.indicateBufferReady(arm.endpoint, false);
    if (length > 0) {
      this.onData(data);
    }
  }
}
