//! OpenEXR through the pure-Rust `exr` crate.
//!
//! Reading takes the first valid layer at its largest resolution level and accepts channels `R`,`G`,`B`
//! (an `A` or any other extra channel is ignored) or a single `Y` (grey), with half, float or uint
//! samples, scanline or tiled, any compression the crate knows. Deep data, luminance/chroma images and
//! other layouts are errors that list the channels found. Writing produces float RGB, ZIP-compressed
//! scanlines in increasing line order.
//!
//! Depends only on the [`Image`] type; it knows nothing of scenes or rendering.

use std::io::{Cursor, Seek, Write};
use std::panic::{AssertUnwindSafe, catch_unwind};

use ::exr::prelude::{self as exrs, ReadChannels as _, ReadLayers as _, WritableImage as _};

use super::Image;

/// Decodes an EXR file's bytes; the message says what is wrong.
pub(crate) fn decode(bytes: &[u8]) -> Result<Image, String> {
    check_sizes(bytes)?;
    // The crate returns errors for bad files; catching a panic as well keeps a decoder bug on some
    // hostile file from taking the whole program down.
    let read = catch_unwind(AssertUnwindSafe(|| {
        exrs::read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_buffered(Cursor::new(bytes))
    }));
    let image = match read {
        Ok(Ok(image)) => image,
        Ok(Err(e)) => return Err(format!("cannot decode EXR: {e}")),
        Err(_) => return Err("cannot decode EXR: the decoder failed on this file".into()),
    };
    let layer = &image.layer_data;
    let (width, height) = (layer.size.x(), layer.size.y());
    let channels = &layer.channel_data.list;
    let find = |name: &str| channels.iter().find(|c| c.name.eq(name)).map(|c| &c.sample_data);
    let planes: Vec<&exrs::FlatSamples> = match (find("R"), find("G"), find("B"), find("Y")) {
        (Some(r), Some(g), Some(b), _) => vec![r, g, b],
        (None, None, None, Some(y)) => vec![y],
        _ => {
            let names: Vec<String> = channels.iter().map(|c| c.name.to_string()).collect();
            return Err(format!(
                "unsupported EXR channel layout [{}]; expected R, G, B (optionally A) or Y",
                names.join(", ")
            ));
        }
    };
    let n = width * height;
    if n == 0 || planes.iter().any(|p| p.len() != n) {
        return Err(format!("EXR layer of {width}×{height} pixels has a wrong sample count"));
    }
    let values: Vec<Vec<f32>> = planes.iter().map(|p| p.values_as_f32().collect()).collect();
    let pixels = (0..n)
        .map(|i| match values.as_slice() {
            [r, g, b] => [r[i], g[i], b[i]],
            [y] => [y[i]; 3],
            _ => unreachable!("one or three planes were selected above"),
        })
        .collect();
    Image::from_pixels(width, height, pixels).ok_or_else(|| "EXR layer has a wrong pixel count".into())
}

/// Largest layer accepted, in pixels (16384 × 16384).
const MAX_PIXELS: usize = 1 << 28;
/// Largest uncompressed layer or block accepted, in bytes.
const MAX_BYTES: usize = 1 << 32;
/// A layer may hold at most this many times the file's size in uncompressed bytes (plus [`SIZE_SLACK`]).
/// Deflate (ZIP) cannot do better than 1032:1, RLE and PIZ do far worse; a header that claims more is
/// corrupt or the file is missing most of its blocks. Without this, a 330 KB file declaring 16384×16384
/// RGB float pixels with one scanline block decoded "successfully" into 6 GB (a hand-built input made
/// while writing the fuzz harness; the exr crate fills missing blocks in).
const MAX_COMPRESSION: usize = 1100;
/// Uncompressed bytes allowed beyond the compression bound (tiny files, headers).
const SIZE_SLACK: usize = 1 << 16;

/// Reads only the headers and refuses sizes the decoder would allocate blindly: a corrupt data window,
/// tile size or channel list can otherwise ask for tens of gigabytes, which aborts the process.
fn check_sizes(bytes: &[u8]) -> Result<(), String> {
    let meta = catch_unwind(AssertUnwindSafe(|| exrs::MetaData::read_from_buffered(Cursor::new(bytes), false)));
    let meta = match meta {
        Ok(Ok(meta)) => meta,
        Ok(Err(e)) => return Err(format!("cannot decode EXR: {e}")),
        Err(_) => return Err("cannot decode EXR: the header reader failed on this file".into()),
    };
    let mut total = 0usize;
    for header in meta.headers.iter() {
        let size = header.layer_size;
        let bpp = header.channels.bytes_per_pixel;
        let block_pixels = match header.blocks {
            ::exr::meta::BlockDescription::Tiles(tiles) => tiles.tile_size.x().checked_mul(tiles.tile_size.y()),
            ::exr::meta::BlockDescription::ScanLines => size.x().checked_mul(header.compression.scan_lines_per_block()),
        };
        let pixels = size.x().checked_mul(size.y());
        let fits =
            |n: Option<usize>| n.is_some_and(|n| n <= MAX_PIXELS && n.checked_mul(bpp).is_some_and(|b| b <= MAX_BYTES));
        if !fits(pixels) || !fits(block_pixels) {
            return Err(format!(
                "EXR layer of {}×{} pixels with {bpp} bytes per pixel is too large or corrupt (at most {MAX_PIXELS} pixels)",
                size.x(),
                size.y()
            ));
        }
        total = total.saturating_add(pixels.unwrap_or(usize::MAX).saturating_mul(bpp));
    }
    let most = bytes.len().saturating_mul(MAX_COMPRESSION).saturating_add(SIZE_SLACK);
    if total > most {
        return Err(format!(
            "EXR header declares {total} bytes of pixel data, more than a {}-byte file can hold \
             (a corrupt header or missing data)",
            bytes.len()
        ));
    }
    Ok(())
}

/// Encodes `image` as float RGB, ZIP-compressed scanlines.
pub(crate) fn encode(image: &Image, out: &mut (impl Write + Seek)) -> Result<(), String> {
    let channels = exrs::SpecificChannels::rgb(|pos: exrs::Vec2<usize>| {
        let [r, g, b] = image.pixels[pos.y() * image.width + pos.x()];
        (r, g, b)
    });
    let encoding = exrs::Encoding {
        compression: exrs::Compression::ZIP16,
        blocks: exrs::Blocks::ScanLines,
        line_order: exrs::LineOrder::Increasing,
    };
    exrs::Image::from_encoded_channels((image.width, image.height), encoding, channels)
        .write()
        .non_parallel()
        .to_buffered(out)
        .map_err(|e| format!("cannot encode EXR: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Image {
        let mut im = Image::new(5, 3);
        for y in 0..3 {
            for x in 0..5 {
                im.set(x, y, [x as f32 * 0.5, y as f32 * 100.0, -(x as f32) - 1e-3]);
            }
        }
        im
    }

    fn encoded(im: &Image) -> Vec<u8> {
        let mut c = Cursor::new(Vec::new());
        encode(im, &mut c).unwrap();
        c.into_inner()
    }

    #[test]
    fn round_trip_is_exact() {
        assert_eq!(decode(&encoded(&sample())).unwrap(), sample());
    }

    /// Writes `samples` as channels of a 2×2 image with the given encoding, through the crate.
    fn any_channels(names_and_values: &[(&str, [f32; 4])], half: bool, tiled: bool) -> Vec<u8> {
        let list: Vec<exrs::AnyChannel<exrs::FlatSamples>> = names_and_values
            .iter()
            .map(|(name, v)| {
                let samples = if half {
                    exrs::FlatSamples::F16(v.iter().map(|&x| ::exr::prelude::f16::from_f32(x)).collect())
                } else {
                    exrs::FlatSamples::F32(v.to_vec())
                };
                exrs::AnyChannel::new(*name, samples)
            })
            .collect();
        let encoding = exrs::Encoding {
            compression: exrs::Compression::PIZ,
            blocks: if tiled { exrs::Blocks::Tiles(exrs::Vec2(16, 16)) } else { exrs::Blocks::ScanLines },
            line_order: exrs::LineOrder::Increasing,
        };
        let channels = exrs::AnyChannels::sort(list.into());
        let mut c = Cursor::new(Vec::new());
        exrs::Image::from_encoded_channels((2, 2), encoding, channels).write().to_buffered(&mut c).unwrap();
        c.into_inner()
    }

    #[test]
    fn reads_rgba_half_tiled_and_grey() {
        let r = [0.0, 1.0, 2.0, 3.0];
        let g = [0.5; 4];
        let b = [0.25, 0.0, 0.0, 8.0];
        let a = [1.0; 4];
        let im = decode(&any_channels(&[("R", r), ("G", g), ("B", b), ("A", a)], true, true)).unwrap();
        assert_eq!((im.width, im.height), (2, 2));
        assert_eq!(im.get(1, 0), [1.0, 0.5, 0.0]);
        assert_eq!(im.get(1, 1), [3.0, 0.5, 8.0]);
        let im = decode(&any_channels(&[("Y", r)], false, false)).unwrap();
        assert_eq!(im.get(0, 1), [2.0; 3]);
    }

    #[test]
    fn unsupported_layouts_list_the_channels() {
        let msg = decode(&any_channels(&[("Z", [0.0; 4]), ("A", [1.0; 4])], false, false)).unwrap_err();
        assert!(msg.contains("[A, Z]") && msg.contains("expected R, G, B"), "{msg}");
        let msg = decode(&any_channels(&[("R", [0.0; 4]), ("G", [1.0; 4])], false, false)).unwrap_err();
        assert!(msg.contains("[G, R]"), "{msg}");
    }

    #[test]
    fn junk_is_an_error_not_a_panic() {
        let good = encoded(&sample());
        assert!(decode(b"").is_err());
        assert!(decode(b"not an exr file at all").is_err());
        for n in [4, 8, 20, 100, good.len() / 2, good.len() - 1] {
            assert!(decode(&good[..n]).is_err(), "prefix {n}");
        }
    }

    /// Regression: a corrupt header once made the decoder ask for 36 GB and abort the process.
    #[test]
    fn corrupt_sizes_are_refused_before_decoding() {
        let good = encoded(&sample());
        let at = good.windows(10).position(|w| w == b"dataWindow").unwrap();
        // box2i after "dataWindow\0box2i\0" and the 4-byte attribute size: xmin, ymin, xmax, ymax.
        let xmax = at + b"dataWindow\0box2i\0".len() + 4 + 8;
        let mut bad = good.clone();
        bad[xmax..xmax + 4].copy_from_slice(&2_000_000_000i32.to_le_bytes());
        let msg = decode(&bad).unwrap_err();
        assert!(msg.contains("EXR"), "{msg}");
        // Cheap deterministic fuzz over byte changes: every outcome is an image or a message.
        let mut state = 12345u64;
        for _ in 0..2000 {
            let mut b = good.clone();
            for _ in 0..3 {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let i = (state >> 33) as usize % b.len();
                b[i] = (state >> 20) as u8;
            }
            let _ = decode(&b);
        }
    }
}
