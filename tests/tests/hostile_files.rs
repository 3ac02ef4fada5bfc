//! Hostile files, second round (issue 49): every byte a texture PNG, a
//! NIfTI volume or a raw volume can make the simulator allocate is bounded
//! before it is allocated, and each refusal is a sentence that names the
//! file — measured in time and with the errors' text.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use tilerast_sim::volume::VolumeData;
use tilerast_sim::Image;
use tilerast_tests::memory::{peak_of, Counting};

#[global_allocator]
static A: Counting = Counting;

fn dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("hostile")
        .join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// CRC-32 (IEEE), as PNG chunks carry it.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let start = out.len();
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
    let crc = crc32(&out[start..]);
    out.extend_from_slice(&crc.to_be_bytes());
}

/// A small PNG whose header claims `w x h` RGBA pixels.
fn png_claiming(w: u32, h: u32) -> Vec<u8> {
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = vec![];
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    chunk(&mut png, b"IHDR", &ihdr);
    // A zlib stream of 16 KB of zeros: far less than the header claims.
    let mut z = flate2::write::ZlibEncoder::new(vec![], flate2::Compression::fast());
    z.write_all(&[0u8; 16 << 10]).unwrap();
    chunk(&mut png, b"IDAT", &z.finish().unwrap());
    chunk(&mut png, b"IEND", &[]);
    png
}

#[test]
fn a_png_claiming_65535_squared_pixels_is_an_error_not_an_abort() {
    let d = dir("png");
    let p = d.join("huge.png");
    std::fs::write(&p, png_claiming(65535, 65535)).unwrap();
    let t = Instant::now();
    let e = Image::load_png(&p).unwrap_err().to_string();
    assert!(t.elapsed() < Duration::from_secs(2));
    assert!(
        e.contains("huge.png") && e.contains("65535 x 65535 pixels: larger than the limit of 4096"),
        "{e}"
    );
    // Within the limit, the same lie is caught by the decoder, still as
    // a sentence.
    std::fs::write(&p, png_claiming(4000, 4000)).unwrap();
    let e = Image::load_png(&p).unwrap_err().to_string();
    assert!(e.starts_with(&p.display().to_string()), "{e}");
}

#[test]
fn a_texture_png_claiming_too_many_pixels_fails_the_scene_with_its_name() {
    let d = dir("texture");
    std::fs::write(d.join("huge.png"), png_claiming(65535, 65535)).unwrap();
    std::fs::copy(
        tilerast_tests::repo().join("assets/models/crate.obj"),
        d.join("crate.obj"),
    )
    .unwrap();
    let scene = d.join("scene.toml");
    std::fs::write(
        &scene,
        "[screen]\nwidth = 32\nheight = 32\nformat = \"rgb565\"\ndepth = true\n\n\
         [[command]]\nkind = \"mesh\"\nobj = \"crate.obj\"\ntexture = \"huge.png\"\n",
    )
    .unwrap();
    // Loading goes on without the texture (a warning), or refuses with
    // the texture's name: never an abort.
    match tilerast_sim::Scene::load(&scene) {
        Ok(s) => assert!(
            s.notes.iter().any(|w| w.contains("huge.png")),
            "{:?}",
            s.notes
        ),
        Err(e) => assert!(e.to_string().contains("huge.png"), "{e}"),
    }
}

/// A NIfTI-1 header (348 bytes and 4 of extension flags) of `dims` voxels
/// of `bitpix` bits, data at `vox_offset`.
fn nifti_header(dims: [i16; 3], datatype: i16, bitpix: i16, vox_offset: f32) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    let dim = [3i16, dims[0], dims[1], dims[2], 1, 1, 1, 1];
    for (i, d) in dim.iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&datatype.to_le_bytes());
    h[72..74].copy_from_slice(&bitpix.to_le_bytes());
    for i in 0..8 {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&1f32.to_le_bytes());
    }
    h[108..112].copy_from_slice(&vox_offset.to_le_bytes());
    h[112..116].copy_from_slice(&1f32.to_le_bytes());
    h[344..348].copy_from_slice(b"n+1\0");
    h
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut z = flate2::write::GzEncoder::new(vec![], flate2::Compression::best());
    z.write_all(bytes).unwrap();
    z.finish().unwrap()
}

fn write(d: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = d.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn load_err(p: &Path) -> String {
    let t = Instant::now();
    let e = VolumeData::load_nifti(p).unwrap_err().to_string();
    assert!(
        t.elapsed() < Duration::from_secs(5),
        "{e}: {:?}",
        t.elapsed()
    );
    assert!(
        e.contains(&*p.file_name().unwrap().to_string_lossy()),
        "{e}"
    );
    e
}

#[test]
fn a_nifti_gzip_bomb_is_refused_from_its_header() {
    let d = dir("nifti");
    // 1024^3 bytes declared, 64 MB of zeros actually compressed (~64 KB):
    // the header alone is refused; nothing is decompressed past it.
    let mut body = nifti_header([1024, 1024, 1024], 2, 8, 352.0);
    body.resize(body.len() + (64 << 20), 0);
    let p = write(&d, "bomb.nii.gz", &gzip(&body));
    assert!(std::fs::metadata(&p).unwrap().len() < 1 << 20);
    let e = load_err(&p);
    assert!(e.contains("exceed the limit of 268435456 bytes"), "{e}");
}

#[test]
fn nifti_errors_are_sentences() {
    let d = dir("nifti-errors");
    let good = {
        let mut b = nifti_header([8, 8, 8], 2, 8, 352.0);
        b.resize(352 + 512, 7);
        b
    };
    // Sanity: the well-formed file loads.
    let p = write(&d, "ok.nii.gz", &gzip(&good));
    assert_eq!(VolumeData::load_nifti(&p).unwrap().dims, [8, 8, 8]);
    // Truncated gzip: not a `Debug` dump.
    let gz = gzip(&good);
    let p = write(&d, "cut.nii.gz", &gz[..gz.len() / 2]);
    let e = load_err(&p);
    assert!(
        e.contains("the gzip stream ends early") && !e.contains("Custom {"),
        "{e}"
    );
    // Data past the end of an uncompressed file.
    let p = write(&d, "short.nii", &good[..352 + 40]);
    assert!(load_err(&p).contains("the file ends early: 392 of 864 bytes"));
    // vox_offset 3e9: readable, not 3000000000.0 or worse.
    let p = write(&d, "far.nii", &nifti_header([8, 8, 8], 2, 8, 3e9));
    let e = load_err(&p);
    assert!(e.contains("vox_offset) is 3e9"), "{e}");
    // A negative side is named as it is written.
    let p = write(&d, "neg.nii", &nifti_header([8, -5, 8], 2, 8, 352.0));
    assert!(load_err(&p).contains("side 1 is -5 voxels"));
    // float64 data with a NaN: refused, not drawn as nothing.
    let mut b = nifti_header([2, 2, 2], 64, 64, 352.0);
    for i in 0..8 {
        let v = if i == 3 { f64::NAN } else { i as f64 };
        b.extend_from_slice(&v.to_le_bytes());
    }
    let p = write(&d, "nan.nii", &b);
    assert!(load_err(&p).contains("1 of 8 voxels are NaN or infinite"));
}

#[test]
fn a_raw_volume_reads_only_what_its_dims_declare() {
    let d = dir("raw");
    let t = Instant::now();
    let e = VolumeData::load_raw(Path::new("/dev/zero"), [1024, 1024, 1024])
        .unwrap_err()
        .to_string();
    assert!(t.elapsed() < Duration::from_secs(1));
    assert!(e.contains("over the limit of 268435456"), "{e}");
    // /dev/zero with small dims: exactly those bytes, a black volume.
    let v = VolumeData::load_raw(Path::new("/dev/zero"), [4, 4, 4]).unwrap();
    assert_eq!(v.density, vec![0; 64]);
    // A short file: how many bytes there were.
    let p = write(&d, "short.raw", &[9u8; 10]);
    let e = VolumeData::load_raw(&p, [4, 4, 4]).unwrap_err().to_string();
    assert!(
        e.contains("short.raw: the file ends early: 10 of the 64 bytes"),
        "{e}"
    );
}

/// A scene file with a `[volume]` of `keys` (the procedural sphere).
fn volume_scene(name: &str, keys: &str) -> PathBuf {
    let d = dir("volume_camera");
    let p = d.join(name);
    std::fs::write(
        &p,
        format!(
            "[screen]\nwidth = 32\nheight = 32\nformat = \"rgb565\"\n\n\
             [volume]\nsource = \"sphere\"\nsize = 8\nslices = 8\n\
             transfer = [[0, 0, 0, 0, 0], [255, 255, 255, 255, 255]]\n{keys}\n"
        ),
    )
    .unwrap();
    p
}

#[test]
fn volume_camera_and_light_errors_name_the_scene_file_and_line() {
    for (name, keys, says) in [
        ("nan_eye.toml", "eye = [nan, 0, 2]", "eye has NaN"),
        ("inf_rotate.toml", "rotate = [0, inf, 0]", "rotate has inf"),
        ("origin_eye.toml", "eye = [0, 0, 0]", "eye = [0, 0, 0]"),
        ("above_eye.toml", "eye = [0, 3, 0]", "eye = [0, 3, 0]"),
        ("huge_eye.toml", "eye = [0, 0, 1e300]", "1e300"),
        ("dark_light.toml", "lights = [[0, 0, 0, 1]]", "lights"),
        (
            "nan_light.toml",
            "lights = [[0, nan, 1, 1]]",
            "a light has NaN",
        ),
    ] {
        let e = tilerast_sim::Scene::load(volume_scene(name, keys))
            .err()
            .unwrap_or_else(|| panic!("{name}: {keys} was accepted"))
            .to_string();
        // `file:line`: the `[volume]` table's line.
        assert!(e.contains(&format!("{name}:6")), "{name}: {e}");
        assert!(e.contains(says), "{name}: {e}");
        assert!(e.len() < 300, "{name}: {e}");
    }
}

#[test]
fn out_of_range_numbers_print_readably() {
    let e = tilerast_sim::Scene::parse_with(
        "[screen]\nwidth = 32\nheight = 32\nformat = \"rgb565\"\n\n[[command]]\nkind = \"span\"\nx = 0\ny = 0\n\
         len = 4\nrgb = [0, 0, 0]\ndrgb = [1e300, 0, 0]\n",
        Path::new("."),
        &tilerast_sim::Limits::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("drgb = 1e300 is out of range"), "{e}");
    assert!(e.len() < 200, "{e}");
}

#[test]
fn binary_junk_in_an_obj_is_reported_with_its_line() {
    let mut src = vec![0xFF, 0xFE, 0x00, 0x01, b'\n'];
    src.extend_from_slice(b"v 0 0 0\nv 1 0 0\nv 0 1 0\n\x07\x08junk\nf 1 2 3\n");
    let o =
        tilerast_sim::obj::parse(&src, "junk.obj", None, &tilerast_sim::Limits::default()).unwrap();
    assert_eq!(o.models[0].triangles.len(), 1);
    let w = o.warnings.join("\n");
    assert!(w.contains("junk.obj:1: not text"), "{w}");
    assert!(w.contains("2 such lines skipped"), "{w}");
}

/// The volume readers hold at most what the limit lets through: a gzip
/// bomb and an endless raw file under a 1 MiB limit allocate a few
/// kilobytes, and a volume that fits allocates its voxels' planes (density
/// and three normal bytes a voxel) and the data once, measured by a
/// counting allocator.
#[test]
fn volume_readers_allocate_within_their_limit() {
    const LIMIT: u64 = 1 << 20;
    let d = dir("volume_memory");
    // 256^3 bytes declared (16 MiB), 16 MiB of zeros compressed (~16 KB).
    let mut bomb = nifti_header([256, 256, 256], 2, 8, 352.0);
    bomb.extend(std::iter::repeat_n(0u8, 1 << 24));
    let bomb = write(&d, "bomb.nii.gz", &gzip(&bomb));
    let (r, peak) = peak_of(|| VolumeData::load_nifti_within(&bomb, LIMIT));
    assert!(r.is_err());
    assert!(peak < 256 << 10, "the bomb: {peak} bytes");
    let (r, peak) =
        peak_of(|| VolumeData::load_raw_within(Path::new("/dev/zero"), [256; 3], LIMIT));
    assert!(r.is_err());
    assert!(peak < 64 << 10, "/dev/zero: {peak} bytes");
    // 64^3 = 256 KiB of voxels: within the limit.
    let mut fits = nifti_header([64, 64, 64], 2, 8, 352.0);
    fits.extend((0..64 * 64 * 64).map(|i| (i % 251) as u8));
    let fits = write(&d, "fits.nii.gz", &gzip(&fits));
    let (v, peak) = peak_of(|| VolumeData::load_nifti_within(&fits, LIMIT).unwrap());
    let voxels = 64 * 64 * 64;
    assert_eq!(v.density.len(), voxels);
    assert!(peak <= 8 * voxels + (256 << 10), "64^3 NIfTI: {peak} bytes");
    let (v, peak) =
        peak_of(|| VolumeData::load_raw_within(Path::new("/dev/zero"), [64; 3], LIMIT).unwrap());
    assert_eq!(v.density.len(), voxels);
    assert!(peak <= 8 * voxels + (256 << 10), "64^3 raw: {peak} bytes");
}
