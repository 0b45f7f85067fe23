//! Which `Host` and `Origin` the server answers, so that a page from elsewhere cannot use the
//! viewer: the page has no authentication, and its WebSocket moves the model (`set_q`) and its
//! `/files/` serve the robot's files.
//!
//! - **DNS rebinding**: a page at `http://evil.example:8080` whose name is made to resolve to
//!   127.0.0.1 reaches this server as the same origin, but its requests carry
//!   `Host: evil.example:8080`. Only names that cannot be rebound are answered: `localhost`, IP
//!   literals (loopback ones, the bound address, any when bound to all interfaces) and names the
//!   application adds ([`HostPolicy::allow`], e.g. the controller's host name on a cell
//!   network), each with the server's port.
//! - **Cross-site requests**: a page at `http://evil.example` may open `ws://127.0.0.1:8080/ws`
//!   (WebSockets are not bound by the same-origin policy) or send requests; browsers then send
//!   its `Origin`. A request with an `Origin` is answered only if that is the server's own
//!   origin (`http://` and the request's `Host`) or a loopback name with the server's port.
//!   Requests without one (same-origin navigation and `GET`s, tools such as curl) are answered.
//!
//! Refused requests get `403 Forbidden`.

use std::net::{IpAddr, SocketAddr};

/// The hosts and origins the server answers.
#[derive(Clone, Debug)]
pub struct HostPolicy {
    bound: SocketAddr,
    names: Vec<String>,
}

/// `host[:port]` split (an IPv6 literal in brackets), the port `None` when absent; `None` when
/// the authority is malformed.
fn split_authority(authority: &str) -> Option<(&str, Option<u16>)> {
    let authority = authority.trim();
    if let Some(rest) = authority.strip_prefix('[') {
        let (host, after) = rest.split_once(']')?;
        return match after {
            "" => Some((host, None)),
            p => Some((host, Some(p.strip_prefix(':')?.parse().ok()?))),
        };
    }
    match authority.rsplit_once(':') {
        Some((host, port)) => Some((host, Some(port.parse().ok()?))),
        None => Some((authority, None)),
    }
}

impl HostPolicy {
    /// The policy of a server bound to `bound` (its actual port), with no extra names.
    pub fn new(bound: SocketAddr) -> Self {
        Self {
            bound,
            names: Vec::new(),
        }
    }

    /// Answers `name` too (a host name of the machine the page is opened by, e.g.
    /// `robot.local`), with the server's port.
    pub fn allow(&mut self, name: &str) {
        let name = name.trim().to_ascii_lowercase();
        if !self.names.contains(&name) {
            self.names.push(name);
        }
    }

    /// Whether `host` (without port) names this server in a way DNS cannot rebind.
    fn host_name_ok(&self, host: &str) -> bool {
        if host.eq_ignore_ascii_case("localhost") {
            return true;
        }
        if let Ok(ip) = host.parse::<IpAddr>() {
            return ip.is_loopback() || ip == self.bound.ip() || self.bound.ip().is_unspecified();
        }
        self.names.iter().any(|n| n.eq_ignore_ascii_case(host))
    }

    /// Whether an authority's port is the server's (`None`: the scheme's default, 80).
    fn port_ok(&self, port: Option<u16>) -> bool {
        port.unwrap_or(80) == self.bound.port()
    }

    /// Whether the request's `Host` header (required by HTTP/1.1) is one this server answers.
    pub fn host_ok(&self, host: Option<&str>) -> bool {
        host.and_then(split_authority)
            .is_some_and(|(h, p)| self.port_ok(p) && self.host_name_ok(h))
    }

    /// Whether a request with `Host` `host` (already accepted) may come from `origin`: absent,
    /// the server's own origin, or a loopback name with the server's port.
    pub fn origin_ok(&self, origin: Option<&str>, host: &str) -> bool {
        let Some(origin) = origin else {
            return true;
        };
        let Some(authority) = origin.trim().strip_prefix("http://") else {
            return false; // "null", https://, other schemes
        };
        if authority.eq_ignore_ascii_case(host.trim()) {
            return true;
        }
        split_authority(authority).is_some_and(|(h, p)| {
            self.port_ok(p)
                && (h.eq_ignore_ascii_case("localhost")
                    || h.parse::<IpAddr>().is_ok_and(|ip| ip.is_loopback()))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_names_and_ip_literals_with_the_port_only() {
        let mut p = HostPolicy::new("127.0.0.1:8080".parse().unwrap());
        for ok in [
            "127.0.0.1:8080",
            "localhost:8080",
            "LocalHost:8080",
            "[::1]:8080",
            "127.0.0.2:8080",
        ] {
            assert!(p.host_ok(Some(ok)), "{ok}");
        }
        for bad in [
            "evil.example:8080",
            "127.0.0.1:8081",
            "127.0.0.1",
            "10.0.0.5:8080",
            "localhost.evil.example:8080",
            "[::1",
            "",
        ] {
            assert!(!p.host_ok(Some(bad)), "{bad}");
        }
        assert!(!p.host_ok(None));
        p.allow("Robot.Local");
        assert!(p.host_ok(Some("robot.local:8080")));
        // Bound to every interface: any IP literal (no name can rebind to it), names not.
        let any = HostPolicy::new("0.0.0.0:80".parse().unwrap());
        assert!(any.host_ok(Some("10.0.0.5")) && any.host_ok(Some("10.0.0.5:80")));
        assert!(!any.host_ok(Some("evil.example")));
    }

    #[test]
    fn origins_are_the_servers_own_or_loopback() {
        let p = HostPolicy::new("127.0.0.1:8080".parse().unwrap());
        let host = "127.0.0.1:8080";
        assert!(p.origin_ok(None, host));
        assert!(p.origin_ok(Some("http://127.0.0.1:8080"), host));
        assert!(p.origin_ok(Some("http://localhost:8080"), host));
        for bad in [
            "http://evil.example",
            "http://evil.example:8080",
            "http://localhost:3000",
            "https://127.0.0.1:8080",
            "null",
            "file://",
        ] {
            assert!(!p.origin_ok(Some(bad), host), "{bad}");
        }
        // Bound to every interface and opened by address: the page's origin is that address.
        let any = HostPolicy::new("0.0.0.0:8080".parse().unwrap());
        assert!(any.origin_ok(Some("http://10.0.0.5:8080"), "10.0.0.5:8080"));
        assert!(!any.origin_ok(Some("http://10.0.0.6:8080"), "10.0.0.5:8080"));
    }
}
