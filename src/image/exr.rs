//! OpenEXR through the pure-Rust `exr` crate.
//!
//! Reading takes the first valid layer at its largest resolution level and accepts channels `R`,`G`,`B`
//! (an `A` or any other extra channel is ignored) or a single `Y` (grey), with half, float or uint
//! samples, scanline or tiled, any compression the crate knows. Deep data, luminance/chroma images and
//! other layouts are errors that list the channels found; a data window offset in the display window
//! (a crop) reads as its own pixels. Writing produces float RGB, ZIP-compressed scanlines in increasing
//! line order, with the display/data windows and text attributes of a [`Metadata`] (text attributes in
//! its order, through [`super::exr_header`], so the bytes do not depend on a hash map's order).
//!
//! Depends only on the [`Image`] type; it knows nothing of scenes or rendering.

use std::io::{Cursor, Seek, Write};
use std::panic::{AssertUnwindSafe, catch_unwind};

use ::exr::prelude::{self as exrs, ReadChannels as _, ReadLayers as _, WritableImage as _};

use super::{Image, Metadata, Window};

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

/// The headers of an EXR file, without its pixels.
fn headers(bytes: &[u8]) -> Result<exrs::MetaData, String> {
    let meta = catch_unwind(AssertUnwindSafe(|| exrs::MetaData::read_from_buffered(Cursor::new(bytes), false)));
    match meta {
        Ok(Ok(meta)) => Ok(meta),
        Ok(Err(e)) => Err(format!("cannot decode EXR: {e}")),
        Err(_) => Err("cannot decode EXR: the header reader failed on this file".into()),
    }
}

/// Reads only the headers and refuses sizes the decoder would allocate blindly: a corrupt data window,
/// tile size or channel list can otherwise ask for tens of gigabytes, which aborts the process.
fn check_sizes(bytes: &[u8]) -> Result<(), String> {
    let meta = headers(bytes)?;
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

/// Encodes `image` as float RGB, ZIP-compressed scanlines, with `meta`'s window and text attributes. The
/// window must already be checked to hold the image (as [`super::write_with`] does).
pub(crate) fn encode(image: &Image, meta: &Metadata, out: &mut (impl Write + Seek)) -> Result<(), String> {
    let channels = exrs::SpecificChannels::rgb(|pos: exrs::Vec2<usize>| {
        let [r, g, b] = image.pixels[pos.y() * image.width + pos.x()];
        (r, g, b)
    });
    let encoding = exrs::Encoding {
        compression: exrs::Compression::ZIP16,
        blocks: exrs::Blocks::ScanLines,
        line_order: exrs::LineOrder::Increasing,
    };
    let mut exr_image = exrs::Image::from_encoded_channels((image.width, image.height), encoding, channels);
    if let Some(w) = meta.window {
        // pbrt-v3's WriteImageEXR for a crop: display window the whole film, data window the crop.
        let coordinate = |v: usize| i32::try_from(v).ok().filter(|&v| v < MAX_COORDINATE);
        let (Some(_), Some(_), Some(ox), Some(oy)) =
            (coordinate(w.full[0]), coordinate(w.full[1]), coordinate(w.origin[0]), coordinate(w.origin[1]))
        else {
            return Err(format!("a {}×{} film is too large for EXR", w.full[0], w.full[1]));
        };
        exr_image.attributes.display_window = exrs::IntegerBounds::new((0, 0), (w.full[0], w.full[1]));
        exr_image.layer_data.attributes.layer_position = exrs::Vec2(ox, oy);
    }
    for (i, (name, value)) in meta.attributes.iter().enumerate() {
        if name.is_empty() || meta.attributes[..i].iter().any(|(n, _)| n == name) {
            return Err(format!("text attribute name {name:?} is empty or given twice"));
        }
        let text = |s: &str| {
            exrs::Text::new_or_none(s)
                .ok_or_else(|| format!("text attribute {name:?}: EXR text holds only Latin-1 characters"))
        };
        set_text(&mut exr_image.layer_data.attributes, name, text(name)?, text(value)?)?;
    }
    if meta.attributes.is_empty() {
        return exr_image.write().non_parallel().to_buffered(out).map_err(|e| format!("cannot encode EXR: {e}"));
    }
    let mut buffer = Cursor::new(Vec::new());
    exr_image.write().non_parallel().to_buffered(&mut buffer).map_err(|e| format!("cannot encode EXR: {e}"))?;
    let mut bytes = buffer.into_inner();
    let names: Vec<String> = meta.attributes.iter().map(|(n, _)| n.clone()).collect();
    super::exr_header::order_text_attributes(&mut bytes, &names)?;
    out.write_all(&bytes).map_err(|e| format!("cannot write: {e}"))
}

/// Window coordinates must stay below this (the `exr` crate's bound, OpenEXR's `INT_MAX / 2`).
const MAX_COORDINATE: i32 = i32::MAX / 2 - 1;

/// Stores a text attribute: the standard text attributes of OpenEXR in their own fields (the crate
/// refuses them as custom ones), any other name as a custom `string` attribute, except a name OpenEXR
/// reserves for an attribute of another type (`dataWindow`, say).
fn set_text(layer: &mut exrs::LayerAttributes, name: &str, key: exrs::Text, value: exrs::Text) -> Result<(), String> {
    let field = match name {
        "name" => &mut layer.layer_name,
        "owner" => &mut layer.owner,
        "comments" => &mut layer.comments,
        "capDate" => &mut layer.capture_date,
        "software" => &mut layer.software_name,
        "view" => &mut layer.view_name,
        "renderingTransform" => &mut layer.rendering_transform_name,
        "lookModTransform" => &mut layer.look_modification_transform_name,
        "wrapmodes" => &mut layer.wrap_mode_name,
        _ if ::exr::meta::header::standard_names::ALL.contains(&name.as_bytes()) => {
            return Err(format!("text attribute {name:?}: OpenEXR reserves this name for another kind of attribute"));
        }
        _ => {
            layer.other.insert(key, exrs::AttributeValue::Text(value));
            return Ok(());
        }
    };
    *field = Some(value);
    Ok(())
}

/// The display and data windows and the text attributes of an EXR file's first header.
pub(crate) fn metadata(bytes: &[u8]) -> Result<Metadata, String> {
    let meta = headers(bytes)?;
    let header = meta.headers.first().ok_or("EXR file without a header")?;
    let window = window_of(header.shared_attributes.display_window, header.data_window());
    Ok(Metadata { window, attributes: super::exr_header::text_attributes(bytes)? })
}

/// Where the data window sits in the display window; `None` when they are the same, or when the data
/// window starts left of or above the display window (which a film crop never does).
fn window_of(display: exrs::IntegerBounds, data: exrs::IntegerBounds) -> Option<Window> {
    if display == data {
        return None;
    }
    let offset = |d: i32, s: i32| usize::try_from(i64::from(d) - i64::from(s)).ok();
    let origin = [offset(data.position.x(), display.position.x())?, offset(data.position.y(), display.position.y())?];
    Some(Window { full: [display.size.x(), display.size.y()], origin })
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
        encode(im, &Metadata::default(), &mut c).unwrap();
        c.into_inner()
    }

    #[test]
    fn round_trip_is_exact() {
        assert_eq!(decode(&encoded(&sample())).unwrap(), sample());
    }

    fn encoded_with(im: &Image, meta: &Metadata) -> Vec<u8> {
        let mut c = Cursor::new(Vec::new());
        encode(im, meta, &mut c).unwrap();
        c.into_inner()
    }

    fn crop_meta() -> Metadata {
        let attributes =
            [("renderer", "cachert"), ("software", "x 1.0"), ("zeta", "last"), ("alpha", "café"), ("b", "")];
        Metadata {
            window: Some(Window { full: [20, 10], origin: [7, 4] }),
            attributes: attributes.iter().map(|(n, v)| (n.to_string(), v.to_string())).collect(),
        }
    }

    #[test]
    fn window_and_text_round_trip_in_order() {
        let bytes = encoded_with(&sample(), &crop_meta());
        assert_eq!(metadata(&bytes).unwrap(), crop_meta());
        // The pixels are the data window's, as before.
        assert_eq!(decode(&bytes).unwrap(), sample());
        let header = exrs::MetaData::read_from_buffered(Cursor::new(&bytes), false).unwrap();
        let h = &header.headers[0];
        assert_eq!(h.shared_attributes.display_window, exrs::IntegerBounds::new((0, 0), (20, 10)));
        assert_eq!(h.data_window(), exrs::IntegerBounds::new((7, 4), (5, 3)));
    }

    #[test]
    fn text_attributes_do_not_depend_on_hash_order() {
        let first = encoded_with(&sample(), &crop_meta());
        for _ in 0..8 {
            assert_eq!(encoded_with(&sample(), &crop_meta()), first);
        }
    }

    #[test]
    fn default_metadata_reads_back_as_default() {
        assert_eq!(metadata(&encoded(&sample())).unwrap(), Metadata::default());
        let whole = Metadata { window: Some(Window { full: [5, 3], origin: [0, 0] }), attributes: vec![] };
        assert_eq!(encoded_with(&sample(), &whole), encoded(&sample()));
    }

    #[test]
    fn bad_text_attributes_are_errors() {
        let mut c = Cursor::new(Vec::new());
        let twice = Metadata { window: None, attributes: vec![("a".into(), "1".into()), ("a".into(), "2".into())] };
        assert!(encode(&sample(), &twice, &mut c).unwrap_err().contains("twice"));
        let wide = Metadata { window: None, attributes: vec![("a".into(), "→".into())] };
        assert!(encode(&sample(), &wide, &mut c).unwrap_err().contains("Latin-1"));
        let reserved = Metadata { window: None, attributes: vec![("dataWindow".into(), "x".into())] };
        assert!(encode(&sample(), &reserved, &mut c).unwrap_err().contains("reserves"), "dataWindow");
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
