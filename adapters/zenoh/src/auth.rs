//! Application-level authentication of supervisory commands and heartbeats.
//!
//! # Theory of operation
//! The sender attaches `HMAC-SHA256(key, key_expr ‖ 0x00 ‖ payload)` (32
//! bytes) to the Zenoh sample as its attachment. The kernel side recomputes
//! it over the key expression the sample arrived on and the exact payload
//! bytes, and compares in constant time. Binding the key expression stops a
//! signed message for one robot or one key being replayed onto another;
//! the strictly increasing sequence number inside the payload (checked by
//! the node) stops a replay onto the same key.
//!
//! The emergency stop is deliberately not authenticated: stopping is always
//! the safe direction, and a stop must work when keys or the supervisor
//! are lost.

use hmac::{Hmac, Mac};
use sha2::Sha256;

type HmacSha256 = Hmac<Sha256>;

/// Length of a signature [bytes].
pub const SIGNATURE_LENGTH: usize = 32;

/// The shared secret of a robot and its authorised supervisors.
#[derive(Clone)]
pub struct CommandKey {
    /// The keyed HMAC state before any message; cloned per message.
    keyed: HmacSha256,
}

impl core::fmt::Debug for CommandKey {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("CommandKey(..)")
    }
}

/// Why a signature was not accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SignatureError {
    /// The sample had no attachment.
    #[error("no signature")]
    Missing,
    /// The attachment is not a valid signature over this key and payload.
    #[error("bad signature")]
    Invalid,
}

impl CommandKey {
    /// A key from `secret` (at least 16 bytes; 32 random bytes advised).
    ///
    /// # Errors
    /// [`crate::AdapterError::Setting`] for a shorter secret.
    pub fn new(secret: &[u8]) -> Result<Self, crate::AdapterError> {
        if secret.len() < 16 {
            return Err(crate::AdapterError::Setting(
                "the command key must be at least 16 bytes",
            ));
        }
        let keyed = HmacSha256::new_from_slice(secret)
            .map_err(|_| crate::AdapterError::Setting("the command key was refused by HMAC"))?;
        Ok(Self { keyed })
    }

    fn mac(&self, key_expr: &str, payload: &[u8]) -> HmacSha256 {
        let mut mac = self.keyed.clone();
        mac.update(key_expr.as_bytes());
        mac.update(&[0]);
        mac.update(payload);
        mac
    }

    /// The signature of `payload` sent on `key_expr`.
    pub fn sign(&self, key_expr: &str, payload: &[u8]) -> [u8; SIGNATURE_LENGTH] {
        self.mac(key_expr, payload).finalize().into_bytes().into()
    }

    /// Checks `signature` of `payload` received on `key_expr`.
    ///
    /// # Errors
    /// [`SignatureError`] when absent or wrong.
    pub fn verify(
        &self,
        key_expr: &str,
        payload: &[u8],
        signature: Option<&[u8]>,
    ) -> Result<(), SignatureError> {
        let signature = signature.ok_or(SignatureError::Missing)?;
        self.mac(key_expr, payload)
            .verify_slice(signature)
            .map_err(|_| SignatureError::Invalid)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_signature_binds_key_expression_and_payload() {
        let key = CommandKey::new(b"0123456789abcdef").unwrap();
        let signature = key.sign("a/b", b"payload");
        assert_eq!(key.verify("a/b", b"payload", Some(&signature)), Ok(()));
        assert_eq!(
            key.verify("a/c", b"payload", Some(&signature)),
            Err(SignatureError::Invalid)
        );
        assert_eq!(
            key.verify("a/b", b"payloaD", Some(&signature)),
            Err(SignatureError::Invalid)
        );
        assert_eq!(
            key.verify("a/b", b"payload", None),
            Err(SignatureError::Missing)
        );
        let other = CommandKey::new(b"fedcba9876543210").unwrap();
        assert_eq!(
            other.verify("a/b", b"payload", Some(&signature)),
            Err(SignatureError::Invalid)
        );
    }

    #[test]
    fn short_keys_are_refused() {
        assert!(CommandKey::new(b"short").is_err());
    }
}
