//! URI and base64 codecs for relative and data URIs: the crates the gltf crate decodes
//! them with (`base64`, `urlencoding`), so a file reads the same through either.

/// Decodes `%XX` escapes in a relative URI (malformed escapes are kept as written; bytes
/// that are not UTF-8 are replaced).
pub(super) fn percent_decode(s: &str) -> String {
    String::from_utf8_lossy(&urlencoding::decode_binary(s.as_bytes())).into_owned()
}

/// Standard base64 (RFC 4648 alphabet, padding optional).
pub fn base64_decode(s: &str) -> Result<Vec<u8>, String> {
    base64::decode(s).map_err(|e| e.to_string())
}

/// Standard base64 with padding.
pub fn base64_encode(data: &[u8]) -> String {
    base64::encode(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_escapes_decode_and_malformed_ones_stay() {
        assert_eq!(percent_decode("my%20model%2Fpart.bin"), "my model/part.bin");
        // An escape at the very end decodes too.
        assert_eq!(percent_decode("a%41"), "aA");
        assert_eq!(percent_decode("100%zz%4"), "100%zz%4");
    }

    #[test]
    fn base64_round_trips_and_refuses_other_characters() {
        let data = [0u8, 1, 2, 250, 251, 252, 253];
        assert_eq!(base64_decode(&base64_encode(&data)).unwrap(), data);
        // Padding is optional.
        assert_eq!(base64_decode("AAEC+vv8/Q").unwrap(), data);
        assert!(base64_decode("AAEC*vv8").is_err());
    }
}
