//! The `[[policy]]` tables `synthesize --out` writes, and the plan text they go with.

use super::*;

pub(super) fn toml_key(name: &str) -> String {
    if !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        name.to_string()
    } else {
        format!("{name:?}")
    }
}

/// The rules as `[[policy]]` tables.
pub(super) fn rules_toml(net: &Net, rules: &[Rule]) -> String {
    let mut out = String::new();
    for r in rules {
        let (pairs, partial): (Vec<(usize, u32)>, bool) = match &r.pattern {
            Pattern::Exact(m) => (
                m.iter()
                    .enumerate()
                    .filter(|&(_, &k)| k > 0)
                    .map(|(i, &k)| (i, k))
                    .collect(),
                false,
            ),
            Pattern::Partial(v) => (v.iter().map(|&(p, k)| (p.index(), k)).collect(), true),
        };
        out.push_str("\n[[policy]]\n");
        let marking: Vec<String> = pairs
            .iter()
            .map(|&(i, k)| format!("{} = {k}", toml_key(&net.places()[i].name)))
            .collect();
        if marking.is_empty() {
            // A catch-all (partial, nothing asked of any place) or the empty marking.
            out.push_str("marking = {}\n");
        } else {
            let _ = writeln!(out, "marking = {{ {} }}", marking.join(", "));
        }
        if partial {
            out.push_str("partial = true\n");
        }
        let choose: Vec<String> = r
            .choose
            .iter()
            .map(|&(t, p)| format!("{} = {p:?}", toml_key(&net.transition(t).name)))
            .collect();
        let _ = writeln!(out, "choose = {{ {} }}", choose.join(", "));
    }
    out
}

pub(super) fn relative_to(target: &Path, dir: &Path) -> PathBuf {
    let target = std::fs::canonicalize(target).unwrap_or_else(|_| target.to_path_buf());
    let dir = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
    let t: Vec<_> = target.components().collect();
    let d: Vec<_> = dir.components().collect();
    let common = t.iter().zip(&d).take_while(|(a, b)| a == b).count();
    let mut out = PathBuf::new();
    for _ in common..d.len() {
        out.push("..");
    }
    for c in &t[common..] {
        out.push(c);
    }
    out
}

/// The plan's text with its `net` path made relative to `dir` (where the output goes).
pub(super) fn rebase_plan(plan: &Path, text: &str, dir: &Path) -> anyhow::Result<String> {
    let file = gspn::plan::PlanFile::parse(plan, text)?;
    let net_path = file.net_path(plan);
    let span = file.net.span();
    let rel = relative_to(&net_path, dir);
    let mut out = String::with_capacity(text.len() + 64);
    out.push_str(&text[..span.start]);
    out.push_str(&format!("{:?}", rel.to_string_lossy()));
    out.push_str(&text[span.end..]);
    if !out.ends_with('\n') {
        out.push('\n');
    }
    Ok(out)
}
