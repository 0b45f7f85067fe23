//! Any bytes: SDO messages decode or are refused, never panic, and re-encode canonically; an
//! SDO client and server fed arbitrary messages never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::canopen::sdo::{AbortCode, Address, Request, Response};
use rl_drivers::proto::canopen::sdo_client::Client;
use rl_drivers::proto::canopen::sdo_server::{Dictionary, Server};

struct Od([u8; 300]);

impl Dictionary for Od {
    fn read(&mut self, a: Address, out: &mut [u8]) -> Result<usize, AbortCode> {
        let n = usize::from(a.sub) % 40;
        out[..n].copy_from_slice(&self.0[..n]);
        if a.index == 0 { Err(AbortCode::NO_OBJECT) } else { Ok(n) }
    }

    fn write(&mut self, a: Address, data: &[u8]) -> Result<(), AbortCode> {
        if a.index == 0 {
            return Err(AbortCode::READ_ONLY);
        }
        let n = data.len().min(300);
        self.0[..n].copy_from_slice(&data[..n]);
        Ok(())
    }
}

fuzz_target!(|data: &[u8]| {
    if let Ok(r) = Request::decode(data) {
        assert_eq!(Request::decode(&r.encode()), Ok(r));
    }
    if let Ok(r) = Response::decode(data) {
        assert_eq!(Response::decode(&r.encode()), Ok(r));
    }
    let mut client = Client::new();
    client.upload(Address::new(0x1008, 0));
    let mut server = Server::new();
    let mut od = Od([0x5A; 300]);
    for m in data.chunks(8) {
        let _ = client.on_response(m);
        let _ = server.on_request(m, &mut od);
    }
});
