//! MP4 video: H.264 (ITU-T H.264, Constrained Baseline as OpenH264 writes it, 4:2:0) in an
//! ISO base media file (ISO/IEC 14496-12/-15), playable by browsers and video players.
//!
//! Frames are converted from RGB to YUV 4:2:0 (BT.601, OpenH264's converter) and encoded by
//! Cisco's OpenH264 on one thread (the same bytes whatever the machine's core count), no frame
//! skipped, a key frame every two seconds. The encoder writes Annex B byte streams (start
//! codes); MP4 wants the sequence and picture parameter sets (SPS, PPS) in the track's `avcC`
//! box and every sample's NAL units prefixed by their 4-byte length instead, which
//! [`annex_b_nal_units`] and [`Mp4Encoder::push`] do. Sample `k` starts at `k` frame durations
//! on a time scale of a thousandth of a frame, so rates such as 29.97 are kept exactly.

use std::io::Cursor;

use openh264::OpenH264API;
use openh264::encoder::{BitRate, Encoder, EncoderConfig, FrameRate, IntraFramePeriod};
use openh264::formats::{RgbaSliceU8, YUVBuffer};

use crate::{FrameSink, RenderError, Rgba};

/// Target bits per pixel and frame: renders are flat shaded surfaces on a plain background,
/// which H.264 keeps sharp at this rate (about 2.5 Mbit/s at 960x540, 30 fps).
const BITS_PER_PIXEL: f64 = 0.16;

/// The NAL units of an Annex B byte stream (each without its `00 00 01` or `00 00 00 01`
/// start code).
pub fn annex_b_nal_units(stream: &[u8]) -> Vec<&[u8]> {
    let mut starts = Vec::new();
    let mut i = 0;
    while i + 3 <= stream.len() {
        if stream[i] == 0 && stream[i + 1] == 0 && stream[i + 2] == 1 {
            starts.push((i, i + 3));
            i += 3;
        } else {
            i += 1;
        }
    }
    let mut out = Vec::new();
    for (k, &(_, body)) in starts.iter().enumerate() {
        let mut end = starts.get(k + 1).map_or(stream.len(), |&(at, _)| at);
        // A 4-byte start code's leading zero belongs to it, not to the unit before.
        while end > body && stream[end - 1] == 0 && k + 1 < starts.len() {
            end -= 1;
        }
        if end > body {
            out.push(&stream[body..end]);
        }
    }
    out
}

/// Encodes frames into an MP4 file held in memory.
pub struct Mp4Encoder {
    encoder: Encoder,
    writer: Option<mp4::Mp4Writer<Cursor<Vec<u8>>>>,
    width: u32,
    height: u32,
    /// Track time scale (ticks per second) and one frame's duration in ticks.
    timescale: u32,
    duration: u32,
    frames: u64,
}

fn mp4_error(e: impl std::fmt::Display) -> RenderError {
    RenderError::Mp4(e.to_string())
}

impl Mp4Encoder {
    /// A video of `width x height` pixels (even, as 4:2:0 needs, at least 16) at `fps`.
    pub fn new(width: u32, height: u32, fps: f64) -> Result<Self, RenderError> {
        if !width.is_multiple_of(2)
            || !height.is_multiple_of(2)
            || width < 16
            || height < 16
            || width > 4096
            || height > 4096
        {
            return Err(RenderError::Size(
                width,
                height,
                "an MP4 (H.264, 4:2:0) needs an even width and height, 16 to 4096 pixels".into(),
            ));
        }
        if !(fps > 0.0 && fps <= 1000.0) {
            return Err(RenderError::Rate(fps, "expected more than 0 and at most 1000 frames per second".into()));
        }
        let bitrate = (BITS_PER_PIXEL * width as f64 * height as f64 * fps).clamp(100_000.0, 50_000_000.0) as u32;
        let config = EncoderConfig::new()
            .bitrate(BitRate::from_bps(bitrate))
            .max_frame_rate(FrameRate::from_hz(fps as f32))
            .skip_frames(false)
            .num_threads(1)
            .intra_frame_period(IntraFramePeriod::from_num_frames((2.0 * fps).round().max(1.0) as u32));
        let encoder = Encoder::with_api_config(OpenH264API::from_source(), config).map_err(mp4_error)?;
        let timescale = (fps * 1000.0).round() as u32;
        Ok(Mp4Encoder { encoder, writer: None, width, height, timescale, duration: 1000, frames: 0 })
    }

    /// Starts the file once the first frame gave the parameter sets.
    fn start(&self, sps: &[u8], pps: &[u8]) -> Result<mp4::Mp4Writer<Cursor<Vec<u8>>>, RenderError> {
        let brand = |s: &str| s.parse::<mp4::FourCC>().map_err(mp4_error);
        let config = mp4::Mp4Config {
            major_brand: brand("isom")?,
            minor_version: 512,
            compatible_brands: vec![brand("isom")?, brand("iso2")?, brand("avc1")?, brand("mp41")?],
            timescale: 1000,
        };
        let mut w = mp4::Mp4Writer::write_start(Cursor::new(Vec::new()), &config).map_err(mp4_error)?;
        w.add_track(&mp4::TrackConfig {
            track_type: mp4::TrackType::Video,
            timescale: self.timescale,
            language: "und".into(),
            media_conf: mp4::MediaConfig::AvcConfig(mp4::AvcConfig {
                width: self.width as u16,
                height: self.height as u16,
                seq_param_set: sps.to_vec(),
                pic_param_set: pps.to_vec(),
            }),
        })
        .map_err(mp4_error)?;
        Ok(w)
    }

    /// The MP4 file's bytes.
    pub fn finish(self) -> Result<Vec<u8>, RenderError> {
        let Some(mut w) = self.writer else { return Err(RenderError::Mp4("no frame to write".into())) };
        w.write_end().map_err(mp4_error)?;
        Ok(w.into_writer().into_inner())
    }
}

impl FrameSink for Mp4Encoder {
    fn push(&mut self, frame: &Rgba) -> Result<(), RenderError> {
        if (frame.width, frame.height) != (self.width, self.height) {
            return Err(RenderError::Mp4(format!(
                "frame {} is {}x{}, the video {}x{}",
                self.frames, frame.width, frame.height, self.width, self.height
            )));
        }
        let yuv =
            YUVBuffer::from_rgb_source(RgbaSliceU8::new(&frame.data, (self.width as usize, self.height as usize)));
        let stream = self.encoder.encode(&yuv).map_err(mp4_error)?.to_vec();
        let (mut sps, mut pps, mut sample, mut sync) = (None, None, Vec::new(), false);
        for nal in annex_b_nal_units(&stream) {
            match nal[0] & 0x1f {
                7 => sps = Some(nal),
                8 => pps = Some(nal),
                t => {
                    sync |= t == 5;
                    sample.extend_from_slice(&(nal.len() as u32).to_be_bytes());
                    sample.extend_from_slice(nal);
                }
            }
        }
        if sample.is_empty() {
            return Err(RenderError::Mp4(format!("the encoder gave no picture for frame {}", self.frames)));
        }
        if self.writer.is_none() {
            let (Some(sps), Some(pps)) = (sps, pps) else {
                return Err(RenderError::Mp4("the first frame came without its parameter sets (SPS, PPS)".into()));
            };
            self.writer = Some(self.start(sps, pps)?);
        }
        let w = self.writer.as_mut().expect("started above");
        let s = mp4::Mp4Sample {
            start_time: self.frames * self.duration as u64,
            duration: self.duration,
            rendering_offset: 0,
            is_sync: sync,
            bytes: bytes::Bytes::from(sample),
        };
        w.write_sample(1, &s).map_err(mp4_error)?;
        self.frames += 1;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn annex_b_units_are_split_at_both_start_codes() {
        let s = [0, 0, 0, 1, 0x67, 1, 2, 0, 0, 1, 0x68, 3, 0, 0, 0, 1, 0x65, 4, 5, 0];
        let u = annex_b_nal_units(&s);
        assert_eq!(u, vec![&[0x67, 1, 2][..], &[0x68, 3][..], &[0x65, 4, 5, 0][..]]);
        assert!(annex_b_nal_units(&[1, 2, 3]).is_empty());
    }

    #[test]
    fn a_video_reads_back_with_its_size_frames_and_rate() {
        let (w, h) = (64u32, 48u32);
        let mut v = Mp4Encoder::new(w, h, 25.0).unwrap();
        for k in 0..10u32 {
            let data = (0..w * h).flat_map(|i| [((i % w + 4 * k) * 4) as u8, 128, (i / w * 5) as u8, 255]).collect();
            v.push(&Rgba { width: w, height: h, data }).unwrap();
        }
        let bytes = v.finish().unwrap();
        let size = bytes.len() as u64;
        let r = mp4::Mp4Reader::read_header(Cursor::new(bytes), size).unwrap();
        let t = r.tracks().get(&1).unwrap();
        assert_eq!((t.width(), t.height()), (64, 48));
        assert_eq!(t.sample_count(), 10);
        assert!((t.frame_rate() - 25.0).abs() < 1e-6, "{}", t.frame_rate());
        assert!(t.duration().as_secs_f64() > 0.39 && t.duration().as_secs_f64() < 0.41);
    }

    #[test]
    fn odd_sizes_are_refused() {
        let e = Mp4Encoder::new(641, 480, 30.0).err().unwrap();
        assert!(e.to_string().contains("even width and height"), "{e}");
    }
}
