//! Natural ordering of file names: `frame_2.obj` before `frame_10.obj`.

use std::cmp::Ordering;

/// Compares two names by runs: digit runs numerically, other runs character by character;
/// ties (such as `01` vs `1`) are broken by plain byte order so the order is total.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut x, mut y) = (a.as_bytes(), b.as_bytes());
    loop {
        match (x.first(), y.first()) {
            (None, None) => return a.cmp(b),
            (None, Some(_)) => return Ordering::Less,
            (Some(_), None) => return Ordering::Greater,
            (Some(c), Some(d)) if c.is_ascii_digit() && d.is_ascii_digit() => {
                let n = x.iter().take_while(|c| c.is_ascii_digit()).count();
                let m = y.iter().take_while(|c| c.is_ascii_digit()).count();
                let (dx, dy) = (&x[..n], &y[..m]);
                let tx = &dx[dx.iter().take_while(|&&c| c == b'0').count()..];
                let ty = &dy[dy.iter().take_while(|&&c| c == b'0').count()..];
                let o = tx.len().cmp(&ty.len()).then_with(|| tx.cmp(ty));
                if o != Ordering::Equal {
                    return o;
                }
                x = &x[n..];
                y = &y[m..];
            }
            (Some(c), Some(d)) => {
                if c != d {
                    return c.cmp(d);
                }
                x = &x[1..];
                y = &y[1..];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orders_numbers_by_value() {
        let mut v = vec!["f10.obj", "f2.obj", "f1.obj", "f01.obj", "g0.obj", "f100.obj", "f.obj"];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(v, vec!["f.obj", "f01.obj", "f1.obj", "f2.obj", "f10.obj", "f100.obj", "g0.obj"]);
        let mut w = ["mesh_0010.ply", "mesh_0009.ply", "mesh_99999999999999999999999.ply"];
        w.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(w[0], "mesh_0009.ply");
    }
}
