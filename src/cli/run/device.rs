//! `--device`: which robot to drive.

use std::net::{SocketAddr, ToSocketAddrs};

use crate::cli::CliError;

/// H7 real-time UDP port.
const H7_PORT: u16 = 10000;
/// H7 R3 TCP port.
const R3_PORT: u16 = 10001;

/// The robot `rl run` drives.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceSpec {
    /// A fake H7 controller in this process on loopback.
    FakeH7,
    /// A MELFA controller: real-time UDP and R3 TCP addresses.
    H7 {
        /// UDP address (port 10000 by default).
        server: SocketAddr,
        /// R3 address (same host, port 10001 by default).
        r3: SocketAddr,
    },
    /// A Coach visualiser.
    Coach {
        /// TCP address (port 11235 by default).
        server: SocketAddr,
    },
}

impl DeviceSpec {
    /// Parses `fake-h7`, `h7://HOST[:PORT][?r3=PORT]` or `coach://HOST[:PORT]`.
    pub fn parse(text: &str) -> Result<Self, CliError> {
        let bad = |why: String| {
            CliError::usage(format!(
                "--device {text}: {why} (use fake-h7, h7://HOST[:PORT][?r3=PORT] or \
                 coach://HOST[:PORT])"
            ))
        };
        if text == "fake-h7" {
            return Ok(Self::FakeH7);
        }
        if let Some(rest) = text.strip_prefix("h7://") {
            let (host, query) = match rest.split_once('?') {
                Some((h, q)) => (h, Some(q)),
                None => (rest, None),
            };
            let server = resolve(host, H7_PORT).map_err(bad)?;
            let r3_port = match query {
                None => R3_PORT,
                Some(q) => q
                    .strip_prefix("r3=")
                    .and_then(|p| p.parse::<u16>().ok())
                    .filter(|&p| p != 0)
                    .ok_or_else(|| bad(format!("`?{q}`: expected ?r3=PORT")))?,
            };
            return Ok(Self::H7 {
                server,
                r3: SocketAddr::new(server.ip(), r3_port),
            });
        }
        if let Some(rest) = text.strip_prefix("coach://") {
            let server = resolve(rest, rl_drivers::coach::DEFAULT_PORT).map_err(bad)?;
            return Ok(Self::Coach { server });
        }
        Err(bad("unknown device".into()))
    }
}

/// `HOST[:PORT]` to an address (the first the resolver gives).
fn resolve(host: &str, default_port: u16) -> Result<SocketAddr, String> {
    if host.is_empty() {
        return Err("no host".into());
    }
    if let Ok(addr) = host.parse::<SocketAddr>() {
        return Ok(addr);
    }
    let with_port = match host.rsplit_once(':') {
        Some((_, port)) if !host.ends_with(']') && port.parse::<u16>().is_ok() => {
            host.to_socket_addrs()
        }
        _ => (
            host.trim_start_matches('[').trim_end_matches(']'),
            default_port,
        )
            .to_socket_addrs(),
    };
    with_port
        .map_err(|e| format!("cannot resolve `{host}`: {e}"))?
        .next()
        .ok_or_else(|| format!("`{host}` has no address"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_parse_with_default_ports() {
        assert_eq!(DeviceSpec::parse("fake-h7").ok(), Some(DeviceSpec::FakeH7));
        assert_eq!(
            DeviceSpec::parse("h7://127.0.0.1").ok(),
            Some(DeviceSpec::H7 {
                server: "127.0.0.1:10000".parse().expect("addr"),
                r3: "127.0.0.1:10001".parse().expect("addr"),
            })
        );
        assert_eq!(
            DeviceSpec::parse("h7://10.0.0.2:2000?r3=2001").ok(),
            Some(DeviceSpec::H7 {
                server: "10.0.0.2:2000".parse().expect("addr"),
                r3: "10.0.0.2:2001".parse().expect("addr"),
            })
        );
        assert_eq!(
            DeviceSpec::parse("coach://127.0.0.1").ok(),
            Some(DeviceSpec::Coach {
                server: "127.0.0.1:11235".parse().expect("addr"),
            })
        );
        for bad in [
            "h7",
            "h7://",
            "h7://1.2.3.4?r3=x",
            "tcp://1.2.3.4",
            "coach://",
        ] {
            let e = DeviceSpec::parse(bad).expect_err(bad);
            assert_eq!(e.exit_code(), 2, "{bad}");
        }
    }
}
