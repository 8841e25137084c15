//! What the fuzz targets share: how a target's first byte picks a protocol
//! variant, the "no silent acceptance" checks of the FRI codec, and the
//! structure-aware kernel session ([`session`]).
//!
//! Each target in `fuzz_targets/` is one decoder or the kernel; it panics
//! (a libFuzzer crash) only when a property fails. The properties are
//! stated where they are asserted.

pub mod session;

use limb_kuka::FriVersion;
use limb_zenoh::auth::CommandKey;
use limb_zenoh::wire::WireFormat;

/// The FRI version a target's selector byte picks (every version is
/// reachable from every input).
pub fn fri_version(selector: u8) -> FriVersion {
    FriVersion::ALL[usize::from(selector) % FriVersion::ALL.len()]
}

/// A deterministic index below `len` (> 0) drawn from `bytes`, so a target
/// picks the same byte to tamper with on every run of the same input.
pub fn pick(bytes: &[u8], len: usize) -> usize {
    let hash = bytes.iter().fold(0x811c_9dc5_u32, |h, b| {
        (h ^ u32::from(*b)).wrapping_mul(0x0100_0193)
    });
    usize::try_from(hash).unwrap_or(0) % len.max(1)
}

/// No silent acceptance by an FRI decoder, for a message `decode` accepted
/// from `datagram` as `version`:
/// * the message is in the version's canonical form: encoding it and
///   decoding the encoding gives the same bytes again (nothing the decoder
///   kept is lost or invented on the way back out);
/// * for the 2.7 framing, any single flipped bit of the accepted datagram
///   (length prefix, payload or CRC) is refused: CRC-32 detects every
///   single-bit error, and a changed prefix no longer matches the length.
pub fn assert_fri_canonical<M>(
    datagram: &[u8],
    message: &M,
    version: FriVersion,
    encode: impl Fn(&M, FriVersion) -> Result<Vec<u8>, limb_kuka::EncodeError>,
    decode: impl Fn(&[u8], FriVersion) -> Result<M, limb_kuka::DecodeError>,
) {
    // A message decoded from ≤ 1500 bytes may re-encode a few bytes longer
    // (a defaulted connection info): too long to send is not a decoder
    // fault, and the sender refuses it.
    if let Ok(encoded) = encode(message, version) {
        let again = decode(&encoded, version).unwrap_or_else(|e| {
            panic!("{version}: own encoding of an accepted message refused: {e}")
        });
        let reencoded = encode(&again, version)
            .unwrap_or_else(|e| panic!("{version}: re-encoding failed: {e}"));
        assert_eq!(encoded, reencoded, "{version}: encoding is not canonical");
    }
    if version.is_framed() {
        let mut tampered = datagram.to_vec();
        let bit = pick(datagram, datagram.len() * 8);
        tampered[bit / 8] ^= 1 << (bit % 8);
        assert!(
            decode(&tampered, version).is_err(),
            "2.7: a datagram with bit {bit} flipped was accepted"
        );
    }
}

/// The key the Zenoh targets sign with.
pub fn command_key() -> CommandKey {
    CommandKey::new(b"limb fuzz key, 16+ bytes").expect("a 24-byte key")
}

/// How a Zenoh target's sample is signed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Signing {
    /// Signed with the node's key over this key expression and payload.
    Genuine,
    /// Signed with the node's key, but for another key expression.
    OtherKeyExpr,
    /// No attachment.
    Missing,
    /// The genuine signature with one bit flipped.
    Tampered,
}

/// A Zenoh sample drawn from a target's input: mode byte (bit 0: CBOR,
/// else JSON; bits 1-2: [`Signing`]), then the payload.
pub struct Sample<'a> {
    /// Wire format of the node.
    pub format: WireFormat,
    /// How `signature` was made.
    pub signing: Signing,
    /// The payload bytes.
    pub payload: &'a [u8],
    /// The attachment, if any.
    pub signature: Option<Vec<u8>>,
}

/// The sample `data` describes, signed for `key_expr` as its mode says.
pub fn zenoh_sample<'a>(data: &'a [u8], key: &CommandKey, key_expr: &str) -> Option<Sample<'a>> {
    let (&mode, payload) = data.split_first()?;
    let format = if mode & 1 == 1 {
        WireFormat::Cbor
    } else {
        WireFormat::Json
    };
    let signing = match (mode >> 1) & 0b11 {
        0 => Signing::Genuine,
        1 => Signing::OtherKeyExpr,
        2 => Signing::Missing,
        _ => Signing::Tampered,
    };
    let signature = match signing {
        Signing::Genuine => Some(key.sign(key_expr, payload).to_vec()),
        Signing::OtherKeyExpr => Some(key.sign("limb/other/@v2/cmd/request", payload).to_vec()),
        Signing::Missing => None,
        Signing::Tampered => {
            let mut signature = key.sign(key_expr, payload).to_vec();
            let bit = pick(payload, signature.len() * 8);
            signature[bit / 8] ^= 1 << (bit % 8);
            Some(signature)
        }
    };
    Some(Sample {
        format,
        signing,
        payload,
        signature,
    })
}

/// No silent acceptance by a wire decoder: a value `decode` accepted
/// re-encodes to bytes that decode to a value with the same encoding (the
/// canonical spelling is stable, so nothing the decoder kept is lost).
pub fn assert_wire_canonical<T>(format: WireFormat, value: &T)
where
    T: serde::Serialize + serde::de::DeserializeOwned,
{
    let encoded = format
        .encode(value)
        .expect("an accepted value that cannot be encoded");
    let again: T = format
        .decode(&encoded)
        .unwrap_or_else(|e| panic!("{format:?}: own encoding of an accepted value refused: {e}"));
    let reencoded = format.encode(&again).expect("re-encoding failed");
    assert_eq!(encoded, reencoded, "{format:?}: encoding is not canonical");
}
