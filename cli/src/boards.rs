//! The serial ports the system lists (`serialport::available_ports`; on Linux read from sysfs,
//! no libudev), the boards among them first: a USB port with the firmware's USB IDs
//! (`control::report::USB_VID`, `USB_PID`) is a board, told apart from another by its USB
//! serial number, which the firmware makes from the flash chip's unique ID (the id its banner
//! shows); every other port is listed as another serial port (a USB-serial adapter may lead to
//! a board's UART0, which has no ID to show). Used by `hexapod boards` and by the error for a
//! port that does not open.

use std::fmt::{self, Display, Formatter};

use control::report::{USB_PID, USB_VID};
use serialport::{SerialPortInfo, SerialPortType};

/// A serial port found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Found {
    /// Its name, to give as `--port`.
    pub port: String,
    /// What it is.
    pub kind: Kind,
}

/// What a port is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Kind {
    /// A board's USB port, with its serial number (the board's id) if the system gives it.
    Board {
        /// The USB serial number.
        serial: Option<String>,
    },
    /// Another USB serial device (an adapter, another microcontroller).
    OtherUsb {
        /// USB vendor ID.
        vid: u16,
        /// USB product ID.
        pid: u16,
        /// Its product name, if it gives one.
        product: Option<String>,
    },
    /// A serial port that is not USB (built in, Bluetooth, a pseudo-terminal the system lists).
    Other,
}

impl Found {
    /// Its name, and for a board its id: a port in a list (the error for a port that does not
    /// open).
    pub fn short(&self) -> String {
        match &self.kind {
            Kind::Board {
                serial: Some(serial),
            } => format!("{} (hexapod-fw board {serial})", self.port),
            Kind::Board { serial: None } => format!("{} (hexapod-fw board)", self.port),
            _ => self.port.clone(),
        }
    }

    /// Whether it is one of our boards.
    pub fn is_board(&self) -> bool {
        matches!(self.kind, Kind::Board { .. })
    }
}

/// The ports `ports` lists, classified: boards first, then the others, each in name order.
pub fn classify(ports: Vec<SerialPortInfo>) -> Vec<Found> {
    let mut found: Vec<Found> = ports
        .into_iter()
        .map(|info| {
            let kind = match info.port_type {
                SerialPortType::UsbPort(usb) if usb.vid == USB_VID && usb.pid == USB_PID => {
                    Kind::Board {
                        serial: usb.serial_number.filter(|s| !s.is_empty()),
                    }
                }
                SerialPortType::UsbPort(usb) => Kind::OtherUsb {
                    vid: usb.vid,
                    pid: usb.pid,
                    product: usb.product.filter(|s| !s.is_empty()),
                },
                _ => Kind::Other,
            };
            Found {
                port: info.port_name,
                kind,
            }
        })
        .collect();
    found.sort_by(|a, b| (!a.is_board(), &a.port).cmp(&(!b.is_board(), &b.port)));
    found
}

/// The ports present now (none if the system cannot list them).
pub fn present() -> Vec<Found> {
    serialport::available_ports()
        .map(classify)
        .unwrap_or_default()
}

impl Display for Found {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let port = &self.port;
        match &self.kind {
            Kind::Board {
                serial: Some(serial),
            } => write!(f, "{port}: a hexapod-fw board, id {serial}"),
            Kind::Board { serial: None } => {
                write!(f, "{port}: a hexapod-fw board (the system gives no id)")
            }
            Kind::OtherUsb { vid, pid, product } => {
                write!(f, "{port}: another USB serial device ({vid:04x}:{pid:04x}")?;
                if let Some(product) = product {
                    write!(f, ", {product}")?;
                }
                write!(f, "; a USB-serial adapter may lead to a board's UART0)")
            }
            Kind::Other => write!(f, "{port}: another serial port"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serialport::UsbPortInfo;

    fn usb(
        name: &str,
        vid: u16,
        pid: u16,
        serial: Option<&str>,
        product: Option<&str>,
    ) -> SerialPortInfo {
        SerialPortInfo {
            port_name: name.into(),
            port_type: SerialPortType::UsbPort(UsbPortInfo {
                vid,
                pid,
                serial_number: serial.map(str::to_string),
                manufacturer: None,
                product: product.map(str::to_string),
            }),
        }
    }

    #[test]
    fn boards_come_first_named_by_their_id_and_other_ports_are_marked() {
        // The pid.codes test IDs, as docs/host-tool.md gives them (not read from the code).
        let found = classify(vec![
            SerialPortInfo {
                port_name: "/dev/ttyS0".into(),
                port_type: SerialPortType::Unknown,
            },
            usb(
                "/dev/ttyUSB0",
                0x0403,
                0x6001,
                Some("A50285BI"),
                Some("FT232R USB UART"),
            ),
            usb(
                "/dev/ttyACM1",
                0x1209,
                0x0001,
                Some("E660C0D1C7AB2F28"),
                None,
            ),
            usb(
                "/dev/ttyACM0",
                0x1209,
                0x0001,
                Some("E6614103E7452D2F"),
                None,
            ),
            usb("/dev/ttyACM2", 0x1209, 0x0002, Some("X"), None),
            usb("/dev/ttyACM3", 0x1209, 0x0001, None, None),
        ]);
        let lines: Vec<String> = found.iter().map(Found::to_string).collect();
        assert_eq!(
            lines,
            [
                "/dev/ttyACM0: a hexapod-fw board, id E6614103E7452D2F",
                "/dev/ttyACM1: a hexapod-fw board, id E660C0D1C7AB2F28",
                "/dev/ttyACM3: a hexapod-fw board (the system gives no id)",
                "/dev/ttyACM2: another USB serial device (1209:0002; a USB-serial adapter may \
                 lead to a board's UART0)",
                "/dev/ttyS0: another serial port",
                "/dev/ttyUSB0: another USB serial device (0403:6001, FT232R USB UART; a \
                 USB-serial adapter may lead to a board's UART0)",
            ]
        );
        assert_eq!(found.iter().filter(|f| f.is_board()).count(), 3);
        assert_eq!(
            found[0].short(),
            "/dev/ttyACM0 (hexapod-fw board E6614103E7452D2F)"
        );
        assert_eq!(found[4].short(), "/dev/ttyS0");
    }
}
