//! What the last frame's entity volumes were, from the copies of each light's indirect draws:
//! how many lights were counted by z-pass (their volumes missed the near plane) and how many by
//! z-fail, and the triangles drawn. `profile` prints it, and tests read which way was taken.

use super::NAME;
use super::SILHOUETTE_COMMAND_WORDS;

/// How one light's entity volumes were drawn, in triangles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct LightTally {
    zfail_sides: u64,
    caps: u64,
    zpass_sides: u64,
}

impl LightTally {
    fn from_words(w: &[u32]) -> LightTally {
        LightTally {
            zfail_sides: u64::from(w[0]) / 3,
            caps: u64::from(w[4]) / 3,
            zpass_sides: u64::from(w[8]) / 3,
        }
    }

    fn zfail(&self) -> bool {
        self.zfail_sides + self.caps > 0
    }

    fn zpass(&self) -> bool {
        self.zpass_sides > 0
    }
}

/// Up to six names, then how many more.
fn list(names: &[&str]) -> String {
    let mut s = names.iter().take(6).copied().collect::<Vec<_>>().join(", ");
    if names.len() > 6 {
        s += &format!(" and {} more", names.len() - 6);
    }
    s
}

/// The lines for a tally of `words` (per round, opaque then translucent, and per light, the
/// light's command words) under lights named `names`: one per round that drew volumes.
pub fn notes(words: &[u32], names: &[&str]) -> Vec<String> {
    let per_round = names.len() * SILHOUETTE_COMMAND_WORDS;
    let mut out = Vec::new();
    for (round, label) in ["", " (translucent round)"].iter().enumerate() {
        let Some(round_words) = words.get(round * per_round..(round + 1) * per_round) else {
            break;
        };
        let tallies: Vec<LightTally> = round_words
            .chunks_exact(SILHOUETTE_COMMAND_WORDS)
            .map(LightTally::from_words)
            .collect();
        let named = |f: &dyn Fn(&LightTally) -> bool| -> Vec<&str> {
            tallies
                .iter()
                .zip(names)
                .filter(|(t, _)| f(t))
                .map(|(_, n)| *n)
                .collect()
        };
        let zpass = named(&|t| t.zpass() && !t.zfail());
        let zfail = named(&|t| t.zfail() && !t.zpass());
        let both = named(&|t| t.zfail() && t.zpass());
        let drawn = zpass.len() + zfail.len() + both.len();
        if drawn == 0 {
            continue;
        }
        let triangles: u64 = tallies.iter().map(|t| t.zfail_sides + t.caps + t.zpass_sides).sum();
        let caps: u64 = tallies.iter().map(|t| t.caps).sum();
        let mut ways = vec![format!("{} by z-pass alone", zpass.len())];
        for (what, lights) in [("z-fail alone", &zfail), ("both (z-fail for some entities)", &both)] {
            if !lights.is_empty() {
                ways.push(format!("{} by {what} ({})", lights.len(), list(lights)));
            }
        }
        out.push(format!(
            "{NAME}: the last frame's entity volumes{label}: of {drawn} lights, {}; {triangles} triangles drawn, {caps} of them caps (z-pass needs none: a light's volumes are counted by z-fail only where they may reach the near plane)",
            ways.join(", ")
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(lights: &[[u32; 3]]) -> Vec<u32> {
        let mut w = vec![0u32; 2 * lights.len() * SILHOUETTE_COMMAND_WORDS];
        for (i, [zf, caps, zp]) in lights.iter().enumerate() {
            let at = i * SILHOUETTE_COMMAND_WORDS;
            (w[at], w[at + 4], w[at + 8]) = (*zf, *caps, *zp);
        }
        w
    }

    #[test]
    fn the_tally_names_the_lights_counted_by_z_fail() {
        let lines = notes(
            &words(&[[0, 0, 30], [6, 12, 0], [3, 3, 9], [0, 0, 0]]),
            &["a", "b", "c", "d"],
        );
        assert_eq!(lines.len(), 1, "{lines:?}");
        let n = &lines[0];
        assert!(
            n.contains("of 3 lights, 1 by z-pass alone, 1 by z-fail alone (b), 1 by both"),
            "{n}"
        );
        assert!(n.contains("21 triangles drawn, 5 of them caps"), "{n}");
        assert!(notes(&words(&[[0, 0, 0]]), &["a"]).is_empty());
    }
}
