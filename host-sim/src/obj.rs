//! Wavefront OBJ and MTL reading for the simulator: bounded, line-numbered
//! and forgiving of what real files from the web contain.
//!
//! Why our own reader: the simulator is an input surface (issue 12), so
//! every byte it reads is bounded ([`Limits`]: file size and line length),
//! every error names the file, line and column, text that is not UTF-8
//! (a Latin-1 comment) is read lossily, one bad vertex only drops the faces
//! that use it, and polygons are triangulated correctly whether convex or
//! not (ear clipping in the polygon's plane; convex ones keep the fan
//! `v0 vi vi+1` every OBJ reader produces).
//!
//! Groups (`g`, `o`) and material changes (`usemtl`) start a new
//! [`Model`], as most readers do; models without faces or lines are
//! dropped. Within a model, vertices are numbered in order of first use by
//! a face or line (a vertex is a position and, when given, a normal).
//!
//! **Time.** Reading is linear in the file size; triangulating a polygon
//! of `n` vertices costs at most `n³` steps for `n <= MAX_EAR_CLIP`
//! (larger polygons, which no real model has, fall back to the fan with a
//! warning), so a file of `B` bytes is read in `O(B)` plus
//! `O(B · MAX_EAR_CLIP²)` in the worst case.

use crate::error::{Error, Location, Result};
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

/// Limits on what the reader accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest file, in bytes (OBJ and MTL alike).
    pub max_bytes: u64,
    /// Longest line, in bytes.
    pub max_line: usize,
}

impl Default for Limits {
    /// 256 MiB files, 64 KiB lines.
    fn default() -> Self {
        Limits {
            max_bytes: 256 << 20,
            max_line: 64 << 10,
        }
    }
}

/// Polygons with more vertices than this are fanned, not ear-clipped.
pub const MAX_EAR_CLIP: usize = 1024;

/// A material from an `.mtl` file (the colours the geometry stage uses).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Material {
    /// `newmtl` name.
    pub name: String,
    /// Ambient colour `Ka`.
    pub ambient: Option<[f32; 3]>,
    /// Diffuse colour `Kd`.
    pub diffuse: Option<[f32; 3]>,
    /// Specular colour `Ks`.
    pub specular: Option<[f32; 3]>,
    /// Specular exponent `Ns`.
    pub shininess: Option<f32>,
    /// Diffuse texture `map_Kd`, resolved against the `.mtl` file's folder
    /// (options before the file name, such as `-s`, are skipped).
    pub diffuse_map: Option<std::path::PathBuf>,
}

/// One group of faces with one material.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Model {
    /// The `g` / `o` name (empty when none).
    pub name: String,
    /// Index into [`Obj::materials`].
    pub material: Option<usize>,
    /// Positions, one per model vertex.
    pub positions: Vec<[f32; 3]>,
    /// Normals, one per model vertex, or empty when the faces give none.
    pub normals: Vec<[f32; 3]>,
    /// Texture coordinates `vt` (`u`, `v`; `v` grows upwards as in every
    /// OBJ), one per model vertex, or empty unless every face gives them.
    pub texcoords: Vec<[f32; 2]>,
    /// Whether each position is finite (a vertex that is not makes the
    /// faces that use it drop, with a warning naming its line).
    pub finite: Vec<bool>,
    /// Triangles, as model vertex indices, in the file's winding.
    pub triangles: Vec<[u32; 3]>,
    /// Line elements (`l`, and `f` with two vertices).
    pub lines: Vec<[u32; 2]>,
}

/// A read OBJ file.
#[derive(Debug, Clone, Default)]
pub struct Obj {
    /// Groups with faces or lines, in file order.
    pub models: Vec<Model>,
    /// Materials of every `mtllib` read.
    pub materials: Vec<Material>,
    /// What the reader skipped or could not find, each naming its line.
    pub warnings: Vec<String>,
}

/// Reads at most `limits.max_bytes` of a file.
pub fn read_bounded(path: &Path, limits: &Limits) -> Result<Vec<u8>> {
    let f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut buf = Vec::new();
    f.take(limits.max_bytes + 1)
        .read_to_end(&mut buf)
        .map_err(|e| Error::io(path, e))?;
    if buf.len() as u64 > limits.max_bytes {
        return Err(Error::TooLarge {
            path: path.to_path_buf(),
            limit: limits.max_bytes,
        });
    }
    Ok(buf)
}

/// An [`Error::Invalid`] at `at`.
fn invalid(at: Location, message: String) -> Error {
    Error::Invalid { at, message }
}

/// Lines of `src` with their 1-based numbers, decoded lossily; a line
/// longer than the limit is an error naming it.
fn lines<'a>(
    src: &'a [u8],
    file: &'a str,
    limits: &'a Limits,
) -> impl Iterator<Item = Result<(usize, String)>> + 'a {
    src.split(|&b| b == b'\n').enumerate().map(move |(i, l)| {
        if l.len() > limits.max_line {
            return Err(Error::LongLine {
                at: Location::at(file, i + 1, None),
                limit: limits.max_line,
            });
        }
        let l = l.strip_suffix(b"\r").unwrap_or(l);
        Ok((i + 1, String::from_utf8_lossy(l).into_owned()))
    })
}

/// Column (1-based) of `word` inside `line` (`word` is a slice of it).
fn column(line: &str, word: &str) -> usize {
    word.as_ptr() as usize - line.as_ptr() as usize + 1
}

fn floats<const K: usize>(
    line: &str,
    words: &mut std::str::SplitWhitespace<'_>,
    at: &dyn Fn(usize) -> Location,
) -> Result<[f32; K]> {
    let mut out = [0.0f32; K];
    for (k, o) in out.iter_mut().enumerate() {
        let w = words.next().ok_or_else(|| {
            invalid(
                at(line.len() + 1),
                format!("expected {K} numbers, found {k}"),
            )
        })?;
        *o = w
            .parse::<f32>()
            .map_err(|_| invalid(at(column(line, w)), format!("`{w}` is not a number")))?;
    }
    Ok(out)
}

/// Reads an OBJ file and the `.mtl` files it names, within `limits`.
pub fn load(path: &Path, limits: &Limits) -> Result<Obj> {
    let src = read_bounded(path, limits)?;
    parse(&src, &path.display().to_string(), path.parent(), limits)
}

/// A vertex as faces name it: position, optional normal (0-based).
/// A face corner: position, texture coordinate and normal indices.
type Corner = (usize, Option<usize>, Option<usize>);

struct Builder {
    model: Model,
    index: HashMap<Corner, u32>,
}

impl Builder {
    fn new(name: String, material: Option<usize>) -> Self {
        Builder {
            model: Model {
                name,
                material,
                ..Model::default()
            },
            index: HashMap::new(),
        }
    }

    fn is_empty(&self) -> bool {
        self.model.triangles.is_empty() && self.model.lines.is_empty()
    }

    fn vertex(
        &mut self,
        c: Corner,
        pos: &[([f32; 3], bool)],
        texcoords: &[[f32; 2]],
        normals: &[[f32; 3]],
    ) -> u32 {
        let m = &mut self.model;
        *self.index.entry(c).or_insert_with(|| {
            let (p, ok) = pos[c.0];
            m.positions.push(p);
            m.finite.push(ok);
            if let Some(t) = c.1 {
                m.texcoords.push(texcoords[t]);
            }
            if let Some(n) = c.2 {
                m.normals.push(normals[n]);
            }
            (m.positions.len() - 1) as u32
        })
    }

    fn finish(mut self, out: &mut Vec<Model>) {
        if self.is_empty() {
            return;
        }
        // Normals only when every vertex has one.
        if self.model.normals.len() != self.model.positions.len() {
            self.model.normals.clear();
        }
        // Texture coordinates likewise.
        if self.model.texcoords.len() != self.model.positions.len() {
            self.model.texcoords.clear();
        }
        out.push(self.model);
    }
}

/// Parses OBJ text; `file` names it in messages, `dir` is where `mtllib`
/// paths start (`None`: materials are not read).
pub fn parse(src: &[u8], file: &str, dir: Option<&Path>, limits: &Limits) -> Result<Obj> {
    let mut obj = Obj::default();
    let mut pos: Vec<([f32; 3], bool)> = Vec::new();
    let mut normals: Vec<[f32; 3]> = Vec::new();
    let mut texcoords: Vec<[f32; 2]> = Vec::new();
    let mut cur = Builder::new(String::new(), None);
    let mut names: HashMap<String, usize> = HashMap::new();
    let mut bad_used = 0usize;
    // The first line that is not text, and how many there are.
    let mut junk: Option<(usize, usize)> = None;
    for l in lines(src, file, limits) {
        let (n, line) = l?;
        let at = |col: usize| Location::at(file, n, Some(col));
        let body = line.split('#').next().unwrap_or("");
        let mut words = body.split_whitespace();
        let Some(key) = words.next() else { continue };
        let rest = || body[column(body, key) - 1 + key.len()..].trim().to_string();
        match key {
            "v" => {
                let p = floats::<3>(&line, &mut words, &at)?;
                let ok = p.iter().all(|v| v.is_finite());
                if !ok {
                    obj.warnings.push(format!(
                        "{}: vertex {} is not finite; the faces that use it are dropped",
                        at(1),
                        pos.len() + 1
                    ));
                }
                pos.push((p, ok));
            }
            "vn" => normals.push(floats::<3>(&line, &mut words, &at)?),
            "vt" => {
                // `u [v [w]]`: a missing `v` is 0, `w` is ignored.
                let u = floats::<1>(&line, &mut words, &at)?[0];
                let v = match words.next() {
                    Some(w) => w.parse::<f32>().map_err(|_| {
                        invalid(at(column(&line, w)), format!("`{w}` is not a number"))
                    })?,
                    None => 0.0,
                };
                if !(u.is_finite() && v.is_finite()) {
                    return Err(invalid(at(1), "texture coordinate is not finite".into()));
                }
                texcoords.push([u, v]);
            }
            "g" | "o" => {
                let name = rest();
                let material = cur.model.material;
                if !cur.is_empty() {
                    std::mem::replace(&mut cur, Builder::new(name, material))
                        .finish(&mut obj.models);
                } else {
                    cur.model.name = name;
                }
            }
            "usemtl" => {
                let name = rest();
                let m = names.get(&name).copied();
                if m.is_none() {
                    obj.warnings.push(format!(
                        "{}: material `{name}` is not defined; its faces are grey",
                        at(1)
                    ));
                }
                if m != cur.model.material && !cur.is_empty() {
                    let name = cur.model.name.clone();
                    std::mem::replace(&mut cur, Builder::new(name, m)).finish(&mut obj.models);
                } else {
                    cur.model.material = m;
                }
            }
            "mtllib" => {
                let Some(dir) = dir else { continue };
                let name = rest();
                let path = dir.join(&name);
                match std::fs::metadata(&path) {
                    Ok(_) => {
                        for m in load_mtl(&path, limits)? {
                            names.insert(m.name.clone(), obj.materials.len());
                            obj.materials.push(m);
                        }
                    }
                    Err(e) => obj.warnings.push(format!(
                        "{}: mtllib {name}: {e}; its materials are missing",
                        at(column(&line, key))
                    )),
                }
            }
            "f" | "l" => {
                let mut corners: Vec<Corner> = Vec::new();
                for w in words {
                    let col = column(&line, w);
                    let mut parts = w.split('/');
                    let index =
                        |s: Option<&str>, len: usize, what: &str| -> Result<Option<usize>> {
                            let Some(s) = s.filter(|s| !s.is_empty()) else {
                                return Ok(None);
                            };
                            let i: i64 = s.parse().map_err(|_| {
                                invalid(at(col), format!("`{w}` is not a vertex reference"))
                            })?;
                            // 1-based, or negative: relative to the end.
                            let k = if i > 0 { i - 1 } else { len as i64 + i };
                            if i == 0 || !(0..len as i64).contains(&k) {
                                return Err(invalid(
                                    at(col),
                                    format!("{what} {i} does not exist ({len} defined so far)"),
                                ));
                            }
                            Ok(Some(k as usize))
                        };
                    let v = index(parts.next(), pos.len(), "vertex")?
                        .ok_or_else(|| invalid(at(col), format!("`{w}` names no vertex")))?;
                    let vt = index(parts.next(), texcoords.len(), "texture coordinate")?;
                    let vn = index(parts.next(), normals.len(), "normal")?;
                    corners.push((v, vt, vn));
                }
                if corners.iter().any(|c| !pos[c.0].1) {
                    bad_used += 1;
                    continue;
                }
                let ids: Vec<u32> = corners
                    .iter()
                    .map(|&c| cur.vertex(c, &pos, &texcoords, &normals))
                    .collect();
                match (key, ids.len()) {
                    (_, 0 | 1) => obj.warnings.push(format!(
                        "{}: `{key}` with {} vertex skipped",
                        at(1),
                        ids.len()
                    )),
                    ("l", _) => cur.model.lines.extend(ids.windows(2).map(|w| [w[0], w[1]])),
                    (_, 2) => {
                        obj.warnings
                            .push(format!("{}: face with two vertices drawn as a line", at(1)));
                        cur.model.lines.push([ids[0], ids[1]]);
                    }
                    _ => {
                        let pts: Vec<[f64; 3]> = corners
                            .iter()
                            .map(|c| pos[c.0].0.map(|v| v as f64))
                            .collect();
                        let tris = triangulate(&pts);
                        if ids.len() > MAX_EAR_CLIP {
                            obj.warnings.push(format!(
                                "{}: polygon of {} vertices fanned, not ear-clipped",
                                at(1),
                                ids.len()
                            ));
                        }
                        cur.model
                            .triangles
                            .extend(tris.iter().map(|t| t.map(|k| ids[k])));
                    }
                }
            }
            // Statements OBJ readers do not know are skipped, as the
            // format says; bytes that are not text are reported, with the
            // first line they are on.
            _ => {
                if line
                    .chars()
                    .any(|c| c == char::REPLACEMENT_CHARACTER || (c.is_control() && c != '\t'))
                {
                    junk.get_or_insert((n, 0)).1 += 1;
                }
            }
        }
    }
    cur.finish(&mut obj.models);
    if let Some((first, count)) = junk {
        obj.warnings.push(format!(
            "{}: not text (bytes that are not UTF-8, or control characters); {count} such \
             line{} skipped",
            Location::at(file, first, None),
            if count == 1 { "" } else { "s" }
        ));
    }
    if bad_used > 0 {
        obj.warnings.push(format!(
            "{file}: {bad_used} faces or lines dropped for a vertex that is not finite"
        ));
    }
    Ok(obj)
}

/// Reads an `.mtl` file's materials.
pub fn load_mtl(path: &Path, limits: &Limits) -> Result<Vec<Material>> {
    let src = read_bounded(path, limits)?;
    let file = path.display().to_string();
    let mut out: Vec<Material> = Vec::new();
    for l in lines(&src, &file, limits) {
        let (n, line) = l?;
        let at = |col: usize| Location::at(file.as_str(), n, Some(col));
        let body = line.split('#').next().unwrap_or("");
        let mut words = body.split_whitespace();
        let Some(key) = words.next() else { continue };
        if key == "newmtl" {
            let name = body[column(body, key) - 1 + key.len()..].trim().to_string();
            out.push(Material {
                name,
                ..Material::default()
            });
            continue;
        }
        let Some(m) = out.last_mut() else { continue };
        match key {
            "Ka" => m.ambient = Some(floats::<3>(&line, &mut words, &at)?),
            "Kd" => m.diffuse = Some(floats::<3>(&line, &mut words, &at)?),
            "Ks" => m.specular = Some(floats::<3>(&line, &mut words, &at)?),
            "Ns" => m.shininess = Some(floats::<1>(&line, &mut words, &at)?[0]),
            "map_Kd" => {
                // `map_Kd [-option value...] file`: the last word is the file.
                if let Some(name) = words.last() {
                    let dir = path.parent().unwrap_or(Path::new("."));
                    m.diffuse_map = Some(dir.join(name));
                }
            }
            _ => {}
        }
    }
    Ok(out)
}

/// Triangles of a simple polygon (corner indices, the polygon's winding):
/// the fan `0 i i+1` when it is convex, else ear clipping in the plane of
/// its Newell normal. A degenerate or self-intersecting rest is fanned.
pub fn triangulate(p: &[[f64; 3]]) -> Vec<[usize; 3]> {
    let n = p.len();
    let fan = |idx: &[usize]| -> Vec<[usize; 3]> {
        (1..idx.len().saturating_sub(1))
            .map(|i| [idx[0], idx[i], idx[i + 1]])
            .collect()
    };
    if n <= 3 {
        return fan(&(0..n).collect::<Vec<_>>());
    }
    // Newell normal; project onto the plane of its largest component.
    let mut nn = [0.0f64; 3];
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        nn[0] += (a[1] - b[1]) * (a[2] + b[2]);
        nn[1] += (a[2] - b[2]) * (a[0] + b[0]);
        nn[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    let k = (0..3)
        .max_by(|&a, &b| nn[a].abs().total_cmp(&nn[b].abs()))
        .unwrap_or(2);
    let (u, v) = ((k + 1) % 3, (k + 2) % 3);
    // Counter-clockwise in (u, v) when the normal's component is positive.
    let s = if nn[k] >= 0.0 { 1.0 } else { -1.0 };
    let q: Vec<(f64, f64)> = p.iter().map(|p| (p[u], p[v] * s)).collect();
    let cross = |a: usize, b: usize, c: usize| {
        (q[b].0 - q[a].0) * (q[c].1 - q[a].1) - (q[b].1 - q[a].1) * (q[c].0 - q[a].0)
    };
    let all: Vec<usize> = (0..n).collect();
    if nn[k] == 0.0 || n > MAX_EAR_CLIP || (0..n).all(|i| cross(i, (i + 1) % n, (i + 2) % n) >= 0.0)
    {
        return fan(&all);
    }
    let inside = |a: usize, b: usize, c: usize, x: usize| {
        cross(a, b, x) >= 0.0 && cross(b, c, x) >= 0.0 && cross(c, a, x) >= 0.0
    };
    let mut rest = all;
    let mut out = Vec::with_capacity(n - 2);
    while rest.len() > 3 {
        let m = rest.len();
        let ear = (0..m).find(|&i| {
            let (a, b, c) = (rest[(i + m - 1) % m], rest[i], rest[(i + 1) % m]);
            cross(a, b, c) > 0.0
                && rest.iter().all(|&x| {
                    x == a
                        || x == b
                        || x == c
                        || q[x] == q[a]
                        || q[x] == q[b]
                        || q[x] == q[c]
                        || !inside(a, b, c, x)
                })
        });
        let Some(i) = ear else {
            out.extend(fan(&rest));
            return out;
        };
        out.push([rest[(i + m - 1) % m], rest[i], rest[(i + 1) % m]]);
        rest.remove(i);
    }
    out.push([rest[0], rest[1], rest[2]]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(p: &[[f64; 3]], t: &[[usize; 3]]) -> f64 {
        t.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| p[i]);
                ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2.0
            })
            .sum()
    }

    #[test]
    fn convex_polygons_keep_the_fan() {
        let sq = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        assert_eq!(triangulate(&sq), [[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn concave_polygon_is_ear_clipped() {
        // A C shape (counter-clockwise): the fan from vertex 0 would cover
        // the notch; ear clipping covers exactly the polygon's area (6).
        let c = [
            [0.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [3.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, 2.0, 0.0],
            [3.0, 2.0, 0.0],
            [3.0, 3.0, 0.0],
            [0.0, 3.0, 0.0],
        ];
        let t = triangulate(&c);
        assert_eq!(t.len(), 6);
        assert!(t.iter().all(|t| area(&c, &[*t]) > 0.0), "{t:?}");
        assert!((area(&c, &t) - 7.0).abs() < 1e-12, "{}", area(&c, &t));
        // Clockwise, and in another plane: still the same area.
        let cw: Vec<[f64; 3]> = c.iter().rev().map(|p| [p[0], 5.0, p[1]]).collect();
        let t = triangulate(&cw);
        let a: f64 = t
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| cw[i]);
                ((b[0] - a[0]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[0] - a[0])).abs() / 2.0
            })
            .sum();
        assert!((a - 7.0).abs() < 1e-12, "{a}");
    }
}
