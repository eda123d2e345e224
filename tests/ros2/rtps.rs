//! Hand-written RTPS packets (OMG DDSI-RTPS 2.5, Section 9), little endian: a participant
//! announcement (SPDP DATA) and HEARTBEATs, to play a hostile or broken peer.
#![allow(dead_code)]

use std::net::Ipv4Addr;

/// `ENTITYID_SPDP_BUILTIN_PARTICIPANT_WRITER` / `_READER` (9.3.1.3).
pub const SPDP_WRITER: [u8; 4] = [0x00, 0x01, 0x00, 0xc2];
pub const SPDP_READER: [u8; 4] = [0x00, 0x01, 0x00, 0xc7];
/// `ENTITYID_SEDP_BUILTIN_PUBLICATIONS_ANNOUNCER` / `_DETECTOR`.
pub const SEDP_PUB_WRITER: [u8; 4] = [0x00, 0x00, 0x03, 0xc2];
pub const SEDP_PUB_READER: [u8; 4] = [0x00, 0x00, 0x03, 0xc7];
/// `ENTITYID_SEDP_BUILTIN_SUBSCRIPTIONS_ANNOUNCER` / `_DETECTOR`.
pub const SEDP_SUB_WRITER: [u8; 4] = [0x00, 0x00, 0x04, 0xc2];
pub const SEDP_SUB_READER: [u8; 4] = [0x00, 0x00, 0x04, 0xc7];

/// The 20-byte message header: "RTPS", version 2.4, a vendor id, the sender's GUID prefix.
fn header(prefix: [u8; 12]) -> Vec<u8> {
    let mut m = b"RTPS".to_vec();
    m.extend([2, 4]); // protocol version
    m.extend([0x01, 0x99]); // vendor id (none registered)
    m.extend(prefix);
    m
}

/// A submessage: id, flags (E = little endian always set), length, body.
fn submessage(m: &mut Vec<u8>, id: u8, flags: u8, body: &[u8]) {
    m.push(id);
    m.push(flags | 0x01);
    m.extend((body.len() as u16).to_le_bytes());
    m.extend(body);
}

/// A parameter of a ParameterList: id, length (padded to 4), value.
fn param(out: &mut Vec<u8>, pid: u16, value: &[u8]) {
    let padded = value.len().div_ceil(4) * 4;
    out.extend(pid.to_le_bytes());
    out.extend((padded as u16).to_le_bytes());
    out.extend(value);
    out.extend(std::iter::repeat_n(0u8, padded - value.len()));
}

/// A UDPv4 locator (kind 1, port, address in the last 4 of 16 bytes).
fn locator(ip: Ipv4Addr, port: u16) -> Vec<u8> {
    let mut l = 1i32.to_le_bytes().to_vec();
    l.extend(u32::from(port).to_le_bytes());
    l.extend([0u8; 12]);
    l.extend(ip.octets());
    l
}

/// A sequence number on the wire: high (i32), low (u32).
fn seq(sn: i64) -> [u8; 8] {
    let mut b = [0u8; 8];
    b[..4].copy_from_slice(&((sn >> 32) as i32).to_le_bytes());
    b[4..].copy_from_slice(&(sn as u32).to_le_bytes());
    b
}

/// Packet 1: participant `prefix` announces itself (SPDP DATA, sequence number 1) with the
/// SEDP publication and subscription announcers and detectors, reachable at `reply`.
pub fn spdp_announcement(prefix: [u8; 12], reply: (Ipv4Addr, u16)) -> Vec<u8> {
    let mut params = vec![0x00, 0x03, 0x00, 0x00]; // PL_CDR_LE encapsulation
    param(&mut params, 0x0015, &[2, 4]); // PID_PROTOCOL_VERSION
    param(&mut params, 0x0016, &[0x01, 0x99]); // PID_VENDORID
    let mut guid = prefix.to_vec();
    guid.extend([0x00, 0x00, 0x01, 0xc1]); // ENTITYID_PARTICIPANT
    param(&mut params, 0x0050, &guid); // PID_PARTICIPANT_GUID
    param(&mut params, 0x0032, &locator(reply.0, reply.1)); // PID_METATRAFFIC_UNICAST_LOCATOR
    param(&mut params, 0x0031, &locator(reply.0, reply.1)); // PID_DEFAULT_UNICAST_LOCATOR
    let mut lease = 100i32.to_le_bytes().to_vec();
    lease.extend(0u32.to_le_bytes());
    param(&mut params, 0x0002, &lease); // PID_PARTICIPANT_LEASE_DURATION: 100 s
    // PID_BUILTIN_ENDPOINT_SET: participant announcer/detector, publications and
    // subscriptions announcers/detectors (bits 0–5).
    param(&mut params, 0x0058, &0x3fu32.to_le_bytes());
    param(&mut params, 0x0001, &[]); // PID_SENTINEL

    let mut body = Vec::new();
    body.extend(0u16.to_le_bytes()); // extraFlags
    body.extend(16u16.to_le_bytes()); // octetsToInlineQos
    body.extend(SPDP_READER);
    body.extend(SPDP_WRITER);
    body.extend(seq(1));
    body.extend(params);
    let mut m = header(prefix);
    submessage(&mut m, 0x15, 0x04, &body); // DATA, D flag: serialized data
    m
}

/// Packet 2: HEARTBEATs from participant `prefix`'s SEDP announcers claiming they hold
/// sequence numbers `first..=last` (count `count`, final flag not set: answer required).
pub fn heartbeats(prefix: [u8; 12], first: i64, last: i64, count: i32) -> Vec<u8> {
    let mut m = header(prefix);
    for (reader, writer) in [
        (SEDP_PUB_READER, SEDP_PUB_WRITER),
        (SEDP_SUB_READER, SEDP_SUB_WRITER),
    ] {
        let mut body = Vec::new();
        body.extend(reader);
        body.extend(writer);
        body.extend(seq(first));
        body.extend(seq(last));
        body.extend(count.to_le_bytes());
        submessage(&mut m, 0x07, 0x00, &body); // HEARTBEAT
    }
    m
}

/// A GAP from participant `prefix`'s SEDP publications announcer: sequence numbers
/// `start..list_base` are not available (gapList empty).
pub fn gap(prefix: [u8; 12], start: i64, list_base: i64) -> Vec<u8> {
    let mut m = header(prefix);
    let mut body = Vec::new();
    body.extend(SEDP_PUB_READER);
    body.extend(SEDP_PUB_WRITER);
    body.extend(seq(start));
    body.extend(seq(list_base));
    body.extend(0u32.to_le_bytes()); // numBits
    submessage(&mut m, 0x08, 0x00, &body); // GAP
    m
}

/// A DATA_FRAG from participant `prefix`'s SEDP publications announcer: fragment 1 (of
/// 1024-byte fragments) of sample `sn`, whose size it claims is `sample_size` bytes (RustDDS
/// allocated and zeroed the whole sample on the first fragment).
pub fn data_frag(prefix: [u8; 12], sn: i64, sample_size: u32) -> Vec<u8> {
    let mut m = header(prefix);
    let mut body = Vec::new();
    body.extend(0u16.to_le_bytes()); // extraFlags
    body.extend(28u16.to_le_bytes()); // octetsToInlineQos
    body.extend(SEDP_PUB_READER);
    body.extend(SEDP_PUB_WRITER);
    body.extend(seq(sn));
    body.extend(1u32.to_le_bytes()); // fragmentStartingNum
    body.extend(1u16.to_le_bytes()); // fragmentsInSubmessage
    body.extend(1024u16.to_le_bytes()); // fragmentSize
    body.extend(sample_size.to_le_bytes()); // sampleSize
    body.extend([0x00, 0x03, 0x00, 0x00]); // PL_CDR_LE encapsulation, then the fragment
    body.extend([0u8; 1020]);
    submessage(&mut m, 0x16, 0x00, &body); // DATA_FRAG
    m
}
