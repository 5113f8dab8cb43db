//! `k/N` shards of a job array: `eddy-precompute --shard` and `eddy sweep --shard` compute
//! every N-th item starting at k.

/// Parses `k/N` (0 <= k < N), with a message for a bad one.
pub fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (k, n) = s.split_once('/').ok_or("expected k/N, e.g. 0/4")?;
    let k: usize = k
        .trim()
        .parse()
        .map_err(|e| format!("shard index `{k}`: {e}"))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|e| format!("shard count `{n}`: {e}"))?;
    if n == 0 || k >= n {
        return Err(format!("shard {k}/{n}: need 0 <= k < N"));
    }
    Ok((k, n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_bad_ones_say_why() {
        assert_eq!(parse_shard("2/5"), Ok((2, 5)));
        assert!(parse_shard("5/5").unwrap_err().contains("0 <= k < N"));
        assert!(parse_shard("1").unwrap_err().contains("k/N"));
        assert!(parse_shard("a/2").unwrap_err().contains("shard index"));
    }
}
