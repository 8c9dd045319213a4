//! Tests for `state.rs`: exact barrier lists for the patterns the renderer
//! uses, and randomized sequences checked against an independent per-subresource
//! reference model and against a small model of synchronization validation.

use super::*;
use ash::vk;
use std::collections::{HashMap, HashSet};

type S = vk::PipelineStageFlags2;
type A = vk::AccessFlags2;
type L = vk::ImageLayout;

const CS: S = S::COMPUTE_SHADER;
const FS: S = S::FRAGMENT_SHADER;
const VS: S = S::VERTEX_SHADER;
const COLOR_OUT: S = S::COLOR_ATTACHMENT_OUTPUT;
const XFER: S = S::ALL_TRANSFER;
const SAMPLED: A = A::SHADER_SAMPLED_READ;
const ST_R: A = A::SHADER_STORAGE_READ;
const ST_W: A = A::SHADER_STORAGE_WRITE;
const ST_RW: A = A::from_raw(ST_R.as_raw() | ST_W.as_raw());
const CA_W: A = A::COLOR_ATTACHMENT_WRITE;
const CA_RW: A = A::from_raw(A::COLOR_ATTACHMENT_READ.as_raw() | CA_W.as_raw());
const NONE_S: S = S::NONE;
const NONE_A: A = A::NONE;

#[allow(clippy::too_many_arguments)]
fn ib(
    range: SubresourceRange,
    src_stages: S,
    src_access: A,
    dst_stages: S,
    dst_access: A,
    old_layout: L,
    new_layout: L,
) -> ImageBarrier {
    ImageBarrier {
        range,
        src_stages,
        src_access,
        dst_stages,
        dst_access,
        old_layout,
        new_layout,
    }
}

fn bb(src_stages: S, src_access: A, dst_stages: S, dst_access: A) -> BufferBarrier {
    BufferBarrier {
        src_stages,
        src_access,
        dst_stages,
        dst_access,
    }
}

// ---------------------------------------------------------------------------
// Access table
// ---------------------------------------------------------------------------

#[test]
fn access_table() {
    let a = Access::ColorAttachmentWrite;
    assert_eq!(
        (a.stages(), a.access(), a.layout(), a.is_write()),
        (COLOR_OUT, CA_RW, L::COLOR_ATTACHMENT_OPTIMAL, true)
    );
    let a = Access::DepthStencilAttachmentWrite;
    assert_eq!(a.stages(), S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS);
    assert_eq!(
        a.access(),
        A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE
    );
    assert_eq!(a.layout(), L::DEPTH_STENCIL_ATTACHMENT_OPTIMAL);
    let a = Access::DepthStencilAttachmentRead;
    assert_eq!(
        (a.access(), a.layout(), a.is_write()),
        (
            A::DEPTH_STENCIL_ATTACHMENT_READ,
            L::DEPTH_STENCIL_READ_ONLY_OPTIMAL,
            false
        )
    );
    let a = Access::Present;
    assert_eq!(
        (a.stages(), a.access(), a.layout(), a.is_write()),
        (NONE_S, NONE_A, L::PRESENT_SRC_KHR, false)
    );
    let a = Access::HostRead;
    assert_eq!((a.stages(), a.access()), (S::HOST, A::HOST_READ));
    let a = Access::StorageWrite { stages: CS };
    assert_eq!(
        (a.stages(), a.access(), a.layout(), a.is_write()),
        (CS, ST_RW, L::GENERAL, true)
    );
    let a = Access::TransferWrite;
    assert_eq!(
        (a.stages(), a.access(), a.layout(), a.is_write()),
        (XFER, A::TRANSFER_WRITE, L::TRANSFER_DST_OPTIMAL, true)
    );
    assert_eq!(Access::VertexRead.layout(), L::UNDEFINED);
}

// ---------------------------------------------------------------------------
// Basic hazards
// ---------------------------------------------------------------------------

#[test]
fn fresh_color_write_then_fragment_sample() {
    let all = SubresourceRange::all(1, 1);
    let mut img = ImageState::new(1, 1);
    assert_eq!(
        img.transition(all, Access::ColorAttachmentWrite),
        vec![ib(
            all,
            NONE_S,
            NONE_A,
            COLOR_OUT,
            CA_RW,
            L::UNDEFINED,
            L::COLOR_ATTACHMENT_OPTIMAL
        )]
    );
    assert_eq!(
        img.transition(all, Access::SampledRead { stages: FS }),
        vec![ib(
            all,
            COLOR_OUT,
            CA_W,
            FS,
            SAMPLED,
            L::COLOR_ATTACHMENT_OPTIMAL,
            L::SHADER_READ_ONLY_OPTIMAL
        )]
    );
    assert_eq!(img.layout(0, 0), L::SHADER_READ_ONLY_OPTIMAL);
}

#[test]
fn read_after_read_same_layout() {
    let all = SubresourceRange::all(1, 1);
    let mut img = ImageState::new(1, 1);
    img.transition(all, Access::ColorAttachmentWrite);
    assert_eq!(img.transition(all, Access::SampledRead { stages: FS }).len(), 1);
    // Same stage and access again: already visible, nothing to do.
    assert_eq!(img.transition(all, Access::SampledRead { stages: FS }), vec![]);
    // A compute reader was not in the earlier barrier's visibility scope. The
    // last write is the layout transition, reached through the stage of the
    // barrier that performed it.
    let sro = L::SHADER_READ_ONLY_OPTIMAL;
    assert_eq!(
        img.transition(all, Access::SampledRead { stages: CS }),
        vec![ib(all, FS, NONE_A, CS, SAMPLED, sro, sro)]
    );
    // Both readers covered now, singly and together.
    assert_eq!(img.transition(all, Access::SampledRead { stages: CS }), vec![]);
    assert_eq!(img.transition(all, Access::SampledRead { stages: FS | CS }), vec![]);
    // A reader spanning a covered and an uncovered stage gets one barrier.
    assert_eq!(
        img.transition(all, Access::SampledRead { stages: VS | FS }),
        vec![ib(all, FS, NONE_A, VS | FS, SAMPLED, sro, sro)]
    );
}

#[test]
fn buffer_readers_need_visibility_per_stage_and_access() {
    let mut buf = BufferState::new();
    assert_eq!(buf.transition(Access::StorageWrite { stages: CS }), None);
    assert_eq!(
        buf.transition(Access::UniformRead { stages: VS }),
        Some(bb(CS, ST_W, VS, A::UNIFORM_READ))
    );
    assert_eq!(buf.transition(Access::UniformRead { stages: VS }), None);
    assert_eq!(
        buf.transition(Access::UniformRead { stages: FS }),
        Some(bb(CS, ST_W, FS, A::UNIFORM_READ))
    );
    // FRAGMENT saw the write as a uniform, not as a storage buffer; and VERTEX
    // only as a uniform. A union of stages × union of accesses would wrongly
    // skip these.
    assert_eq!(
        buf.transition(Access::StorageRead { stages: FS }),
        Some(bb(CS, ST_W, FS, ST_R))
    );
    assert_eq!(
        buf.transition(Access::StorageRead { stages: VS }),
        Some(bb(CS, ST_W, VS, ST_R))
    );
    assert_eq!(buf.transition(Access::UniformRead { stages: VS | FS }), None);
    assert_eq!(buf.transition(Access::StorageRead { stages: VS | FS }), None);
}

#[test]
fn write_after_read_and_write_after_write() {
    let all = SubresourceRange::all(1, 1);
    let g = L::GENERAL;
    let mut img = ImageState::new(1, 1);
    assert_eq!(
        img.transition(all, Access::StorageWrite { stages: CS }),
        vec![ib(all, NONE_S, NONE_A, CS, ST_RW, L::UNDEFINED, g)]
    );
    // RAW, same layout: a memory dependency without a layout change.
    assert_eq!(
        img.transition(all, Access::StorageRead { stages: FS }),
        vec![ib(all, CS, ST_W, FS, ST_R, g, g)]
    );
    // WAR: execution dependency on the reader only.
    assert_eq!(
        img.transition(all, Access::StorageWrite { stages: CS }),
        vec![ib(all, FS, NONE_A, CS, ST_RW, g, g)]
    );
    // WAW.
    assert_eq!(
        img.transition(all, Access::StorageWrite { stages: CS }),
        vec![ib(all, CS, ST_W, CS, ST_RW, g, g)]
    );
    // WAR with a layout change: the transition waits for the readers and the
    // (already visible) transition before them.
    let sro = L::SHADER_READ_ONLY_OPTIMAL;
    img.transition(all, Access::SampledRead { stages: FS });
    img.transition(all, Access::SampledRead { stages: CS });
    assert_eq!(
        img.transition(all, Access::ColorAttachmentWrite),
        vec![ib(
            all,
            FS | CS,
            NONE_A,
            COLOR_OUT,
            CA_RW,
            sro,
            L::COLOR_ATTACHMENT_OPTIMAL
        )]
    );
    // WAW with a layout change.
    assert_eq!(
        img.transition(all, Access::TransferWrite),
        vec![ib(
            all,
            COLOR_OUT,
            CA_W,
            XFER,
            A::TRANSFER_WRITE,
            L::COLOR_ATTACHMENT_OPTIMAL,
            L::TRANSFER_DST_OPTIMAL
        )]
    );
}

#[test]
fn read_after_read_with_layout_change_is_a_write() {
    let all = SubresourceRange::all(1, 1);
    let (g, sro) = (L::GENERAL, L::SHADER_READ_ONLY_OPTIMAL);
    let mut img = ImageState::new(1, 1);
    img.transition(all, Access::StorageWrite { stages: CS });
    assert_eq!(
        img.transition(all, Access::SampledRead { stages: FS }),
        vec![ib(all, CS, ST_W, FS, SAMPLED, g, sro)]
    );
    // Back to GENERAL for a storage read: the transition must wait for the
    // sampled reader (WAR) and chains after the first transition through FS.
    assert_eq!(
        img.transition(all, Access::StorageRead { stages: CS }),
        vec![ib(all, FS, NONE_A, CS, ST_R, sro, g)]
    );
    // The second transition is now the last write; a fragment storage reader
    // needs it made visible.
    assert_eq!(
        img.transition(all, Access::StorageRead { stages: FS }),
        vec![ib(all, CS, NONE_A, FS, ST_R, g, g)]
    );
    // And a write waits for both readers.
    assert_eq!(
        img.transition(all, Access::StorageWrite { stages: CS }),
        vec![ib(all, CS | FS, NONE_A, CS, ST_RW, g, g)]
    );
}

#[test]
fn discard() {
    let all = SubresourceRange::all(1, 1);
    let (cao, sro) = (L::COLOR_ATTACHMENT_OPTIMAL, L::SHADER_READ_ONLY_OPTIMAL);
    let mut img = ImageState::new(1, 1);
    img.transition(all, Access::ColorAttachmentWrite);
    img.transition(all, Access::SampledRead { stages: FS });
    // Discarding drops the old layout but still waits for the reader.
    assert_eq!(
        img.transition_discard(all, Access::ColorAttachmentWrite),
        vec![ib(all, FS, NONE_A, COLOR_OUT, CA_RW, L::UNDEFINED, cao)]
    );
    // Unread write then discard: still a WAW dependency.
    assert_eq!(
        img.transition_discard(all, Access::TransferWrite),
        vec![ib(
            all,
            COLOR_OUT,
            CA_W,
            XFER,
            A::TRANSFER_WRITE,
            L::UNDEFINED,
            L::TRANSFER_DST_OPTIMAL
        )]
    );
    // Same layout: identical to a plain transition (no pointless transition).
    let mut a = img.clone();
    assert_eq!(
        img.transition_discard(all, Access::TransferWrite),
        a.transition(all, Access::TransferWrite)
    );
    assert_eq!(img.layout(0, 0), L::TRANSFER_DST_OPTIMAL);
    let _ = sro;
}

#[test]
fn swapchain_frame() {
    let all = SubresourceRange::all(1, 1);
    let mut img = ImageState::external(1, 1, L::UNDEFINED, COLOR_OUT, NONE_A);
    assert_eq!(
        img.transition(all, Access::ColorAttachmentWrite),
        vec![ib(
            all,
            COLOR_OUT,
            NONE_A,
            COLOR_OUT,
            CA_RW,
            L::UNDEFINED,
            L::COLOR_ATTACHMENT_OPTIMAL
        )]
    );
    assert_eq!(
        img.transition(all, Access::ColorAttachmentWrite),
        vec![ib(
            all,
            COLOR_OUT,
            CA_W,
            COLOR_OUT,
            CA_RW,
            L::COLOR_ATTACHMENT_OPTIMAL,
            L::COLOR_ATTACHMENT_OPTIMAL
        )]
    );
    assert_eq!(
        img.transition(all, Access::Present),
        vec![ib(
            all,
            COLOR_OUT,
            CA_W,
            NONE_S,
            NONE_A,
            L::COLOR_ATTACHMENT_OPTIMAL,
            L::PRESENT_SRC_KHR
        )]
    );
    assert_eq!(img.transition(all, Access::Present), vec![]);
}

#[test]
fn depth_prepass_then_read_only_and_sampled() {
    let all = SubresourceRange::all(1, 1);
    let tests = S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS;
    let (dsa, dsro) = (L::DEPTH_STENCIL_ATTACHMENT_OPTIMAL, L::DEPTH_STENCIL_READ_ONLY_OPTIMAL);
    let ds_w = A::DEPTH_STENCIL_ATTACHMENT_WRITE;
    let ds_r = A::DEPTH_STENCIL_ATTACHMENT_READ;
    let mut img = ImageState::new(1, 1);
    assert_eq!(
        img.transition_discard(all, Access::DepthStencilAttachmentWrite),
        vec![ib(all, NONE_S, NONE_A, tests, ds_r | ds_w, L::UNDEFINED, dsa)]
    );
    assert_eq!(
        img.transition(all, Access::DepthStencilAttachmentRead),
        vec![ib(all, tests, ds_w, tests, ds_r, dsa, dsro)]
    );
    // Sampled in the same read-only layout: visibility only.
    assert_eq!(
        img.transition(all, Access::DepthSampledRead { stages: FS }),
        vec![ib(all, tests, NONE_A, FS, SAMPLED, dsro, dsro)]
    );
    assert_eq!(img.transition(all, Access::DepthStencilAttachmentRead), vec![]);
}

#[test]
fn with_initial_states() {
    let all = SubresourceRange::all(2, 1);
    // Left sampled by the fragment shader last frame.
    let mut img = ImageState::with_initial(2, 1, Access::SampledRead { stages: FS });
    assert_eq!(img.layout(1, 0), L::SHADER_READ_ONLY_OPTIMAL);
    assert_eq!(img.transition(all, Access::SampledRead { stages: FS }), vec![]);
    assert_eq!(
        img.transition(all, Access::ColorAttachmentWrite),
        vec![ib(
            all,
            FS,
            NONE_A,
            COLOR_OUT,
            CA_RW,
            L::SHADER_READ_ONLY_OPTIMAL,
            L::COLOR_ATTACHMENT_OPTIMAL
        )]
    );
    // Left written by a compute pass.
    let mut img = ImageState::with_initial(2, 1, Access::StorageWrite { stages: CS });
    assert_eq!(
        img.transition(all, Access::StorageRead { stages: CS }),
        vec![ib(all, CS, ST_W, CS, ST_R, L::GENERAL, L::GENERAL)]
    );
    let mut buf = BufferState::with_initial(Access::HostRead);
    assert_eq!(
        buf.transition(Access::TransferWrite),
        Some(bb(S::HOST, NONE_A, XFER, A::TRANSFER_WRITE))
    );
}

// ---------------------------------------------------------------------------
// Subresources and merging
// ---------------------------------------------------------------------------

#[test]
fn mip_pyramid() {
    const MIPS: u32 = 8;
    let (g, sro) = (L::GENERAL, L::SHADER_READ_ONLY_OPTIMAL);
    let mut img = ImageState::new(MIPS, 1);
    assert_eq!(
        img.transition(SubresourceRange::mip(0), Access::StorageWrite { stages: CS }),
        vec![ib(SubresourceRange::mip(0), NONE_S, NONE_A, CS, ST_RW, L::UNDEFINED, g)]
    );
    for n in 1..MIPS {
        let src = SubresourceRange::mip(n - 1);
        let dst = SubresourceRange::mip(n);
        assert_eq!(
            img.transition(src, Access::SampledRead { stages: CS }),
            vec![ib(src, CS, ST_W, CS, SAMPLED, g, sro)],
            "read of mip {}",
            n - 1
        );
        assert_eq!(
            img.transition(dst, Access::StorageWrite { stages: CS }),
            vec![ib(dst, NONE_S, NONE_A, CS, ST_RW, L::UNDEFINED, g)],
            "write of mip {n}"
        );
        for m in 0..MIPS {
            let want = if m < n {
                sro
            } else if m == n {
                g
            } else {
                L::UNDEFINED
            };
            assert_eq!(img.layout(m, 0), want, "mip {m} after step {n}");
        }
    }
    // Whole image sampled in the fragment shader: mips 0..7 need visibility of
    // their (compute-side) transition only; mip 7 a real transition.
    assert_eq!(
        img.transition(SubresourceRange::full(), Access::SampledRead { stages: FS }),
        vec![
            ib(SubresourceRange::mips(0, 7), CS, NONE_A, FS, SAMPLED, sro, sro),
            ib(SubresourceRange::mip(7), CS, ST_W, FS, SAMPLED, g, sro),
        ]
    );
    assert!((0..MIPS).all(|m| img.layout(m, 0) == sro));
    assert_eq!(
        img.transition(SubresourceRange::full(), Access::SampledRead { stages: FS }),
        vec![]
    );
}

#[test]
fn cube_layer_write_then_read_all() {
    let (mips, layers) = (3, 6);
    let face2 = SubresourceRange::layer_all_mips(2);
    let sro = L::SHADER_READ_ONLY_OPTIMAL;
    let tdo = L::TRANSFER_DST_OPTIMAL;

    // Fresh cube: only face 2 written; reading all faces transitions the other
    // faces from UNDEFINED (reading garbage is the caller's business).
    let mut img = ImageState::new(mips, layers);
    assert_eq!(
        img.transition(face2, Access::TransferWrite),
        vec![ib(
            SubresourceRange::new(0, 3, 2, 1),
            NONE_S,
            NONE_A,
            XFER,
            A::TRANSFER_WRITE,
            L::UNDEFINED,
            tdo
        )]
    );
    assert_eq!(
        img.transition(SubresourceRange::full(), Access::SampledRead { stages: FS }),
        vec![
            ib(
                SubresourceRange::new(0, 3, 0, 2),
                NONE_S,
                NONE_A,
                FS,
                SAMPLED,
                L::UNDEFINED,
                sro
            ),
            ib(
                SubresourceRange::new(0, 3, 2, 1),
                XFER,
                A::TRANSFER_WRITE,
                FS,
                SAMPLED,
                tdo,
                sro
            ),
            ib(
                SubresourceRange::new(0, 3, 3, 3),
                NONE_S,
                NONE_A,
                FS,
                SAMPLED,
                L::UNDEFINED,
                sro
            ),
        ]
    );
    // Now uniform: re-render face 2, mip 0 only, and read everything again.
    let cao = L::COLOR_ATTACHMENT_OPTIMAL;
    assert_eq!(
        img.transition(SubresourceRange::mip_layer(0, 2), Access::ColorAttachmentWrite),
        vec![ib(
            SubresourceRange::mip_layer(0, 2),
            FS,
            NONE_A,
            COLOR_OUT,
            CA_RW,
            sro,
            cao
        )]
    );
    assert_eq!(
        img.transition(SubresourceRange::all(mips, layers), Access::SampledRead { stages: FS }),
        vec![ib(
            SubresourceRange::mip_layer(0, 2),
            COLOR_OUT,
            CA_W,
            FS,
            SAMPLED,
            cao,
            sro
        )]
    );
    for m in 0..mips {
        for l in 0..layers {
            assert_eq!(img.layout(m, l), sro);
        }
    }
}

#[test]
fn merging_uniform_and_split() {
    // Uniform: one barrier for everything.
    let mut img = ImageState::new(8, 4);
    let all = SubresourceRange::all(8, 4);
    assert_eq!(
        img.transition(all, Access::TransferWrite),
        vec![ib(
            all,
            NONE_S,
            NONE_A,
            XFER,
            A::TRANSFER_WRITE,
            L::UNDEFINED,
            L::TRANSFER_DST_OPTIMAL
        )]
    );
    // Mips 0..4 one state, 4..8 another: two barriers.
    let lo = SubresourceRange::new(0, 4, 0, 4);
    let hi = SubresourceRange::new(4, 4, 0, 4);
    assert_eq!(img.transition(hi, Access::StorageWrite { stages: CS }).len(), 1);
    assert_eq!(
        img.transition(all, Access::SampledRead { stages: FS }),
        vec![
            ib(
                lo,
                XFER,
                A::TRANSFER_WRITE,
                FS,
                SAMPLED,
                L::TRANSFER_DST_OPTIMAL,
                L::SHADER_READ_ONLY_OPTIMAL
            ),
            ib(hi, CS, ST_W, FS, SAMPLED, L::GENERAL, L::SHADER_READ_ONLY_OPTIMAL),
        ]
    );
}

#[test]
fn merging_layer_stripes_and_blocks() {
    let sro = L::SHADER_READ_ONLY_OPTIMAL;
    let g = L::GENERAL;
    let read = Access::SampledRead { stages: FS };
    // Odd layers differ from even ones, across all mips: one barrier per
    // stripe of layers (the mip-wise sweep would need one per cell row).
    let mut img = ImageState::with_initial(4, 4, Access::StorageWrite { stages: CS });
    img.transition(SubresourceRange::new(0, 4, 1, 1), read);
    img.transition(SubresourceRange::new(0, 4, 3, 1), read);
    let got = img.transition(SubresourceRange::all(4, 4), read);
    assert_eq!(got.len(), 2, "{got:#?}");
    assert_eq!(
        got[0],
        ib(SubresourceRange::new(0, 4, 0, 1), CS, ST_W, FS, SAMPLED, g, sro)
    );
    assert_eq!(
        got[1],
        ib(SubresourceRange::new(0, 4, 2, 1), CS, ST_W, FS, SAMPLED, g, sro)
    );

    // A 2x2 block inside a uniform 4x4: the surround needs 4 rectangles.
    let mut img = ImageState::with_initial(4, 4, Access::StorageWrite { stages: CS });
    img.transition(SubresourceRange::new(1, 2, 1, 2), Access::TransferWrite);
    let got = img.transition(SubresourceRange::all(4, 4), read);
    assert_eq!(got.len(), 5, "{got:#?}");
    assert_eq!(
        got.iter()
            .filter(|b| b.old_layout == L::TRANSFER_DST_OPTIMAL)
            .map(|b| b.range)
            .collect::<Vec<_>>(),
        vec![SubresourceRange::new(1, 2, 1, 2)]
    );
    assert_eq!(
        got.iter().map(|b| b.range.mip_count * b.range.layer_count).sum::<u32>(),
        16
    );

    // A sub-range transition reports ranges in image coordinates.
    let mut img = ImageState::new(6, 3);
    let r = SubresourceRange::new(2, 3, 1, 2);
    assert_eq!(
        img.transition(r, Access::TransferWrite),
        vec![ib(
            r,
            NONE_S,
            NONE_A,
            XFER,
            A::TRANSFER_WRITE,
            L::UNDEFINED,
            L::TRANSFER_DST_OPTIMAL
        )]
    );
    assert_eq!(img.layout(1, 1), L::UNDEFINED);
    assert_eq!(img.layout(2, 0), L::UNDEFINED);
    assert_eq!(img.layout(4, 2), L::TRANSFER_DST_OPTIMAL);
    assert_eq!(img.layout(5, 2), L::UNDEFINED);
}

#[test]
fn remaining_counts_resolve() {
    let img = ImageState::new(5, 3);
    assert_eq!(img.resolve(SubresourceRange::full()), SubresourceRange::all(5, 3));
    assert_eq!(
        img.resolve(SubresourceRange::mip_all_layers(4)),
        SubresourceRange::new(4, 1, 0, 3)
    );
    assert_eq!(
        img.resolve(SubresourceRange::layer_all_mips(1)),
        SubresourceRange::new(0, 5, 1, 1)
    );
}

#[test]
#[should_panic]
fn out_of_range_panics() {
    ImageState::new(2, 1).transition(SubresourceRange::mips(1, 2), Access::TransferWrite);
}

#[test]
#[should_panic]
fn buffer_access_on_image_panics() {
    ImageState::new(1, 1).transition(SubresourceRange::full(), Access::VertexRead);
}

#[test]
fn lpv_ping_pong() {
    let one = SubresourceRange::all(1, 1);
    let (g, sro) = (L::GENERAL, L::SHADER_READ_ONLY_OPTIMAL);
    let read = Access::SampledRead { stages: CS };
    let write = Access::StorageWrite { stages: CS };

    // Sampled reads: every step flips both images' layouts.
    let mut imgs = [ImageState::new(1, 1), ImageState::new(1, 1)];
    assert_eq!(
        imgs[0].transition(one, write),
        vec![ib(one, NONE_S, NONE_A, CS, ST_RW, L::UNDEFINED, g)]
    );
    for step in 1..6 {
        let (r, w) = ((step + 1) % 2, step % 2);
        assert_eq!(
            imgs[r].transition(one, read),
            vec![ib(one, CS, ST_W, CS, SAMPLED, g, sro)],
            "step {step} read"
        );
        let want = if step == 1 {
            ib(one, NONE_S, NONE_A, CS, ST_RW, L::UNDEFINED, g)
        } else {
            // WAR on the sampled reads of the previous step, with a transition.
            ib(one, CS, NONE_A, CS, ST_RW, sro, g)
        };
        assert_eq!(imgs[w].transition(one, write), vec![want], "step {step} write");
    }
    // Final gather in the fragment shader (image 1 was written last).
    assert_eq!(
        imgs[1].transition(one, Access::SampledRead { stages: FS }),
        vec![ib(one, CS, ST_W, FS, SAMPLED, g, sro)]
    );

    // Storage reads: everything stays GENERAL, RAW and WAR dependencies only.
    let read = Access::StorageRead { stages: CS };
    let mut imgs = [ImageState::new(1, 1), ImageState::new(1, 1)];
    imgs[0].transition(one, write);
    imgs[1].transition(one, write);
    for step in 1..6 {
        let (r, w) = ((step + 1) % 2, step % 2);
        assert_eq!(
            imgs[r].transition(one, read),
            vec![ib(one, CS, ST_W, CS, ST_R, g, g)],
            "step {step}"
        );
        let want = if step == 1 {
            ib(one, CS, ST_W, CS, ST_RW, g, g) // WAW on the initial clear
        } else {
            ib(one, CS, NONE_A, CS, ST_RW, g, g)
        };
        assert_eq!(imgs[w].transition(one, write), vec![want], "step {step}");
    }
}

#[test]
fn buffers() {
    let mut buf = BufferState::new();
    assert_eq!(buf.transition(Access::TransferWrite), None);
    assert_eq!(
        buf.transition(Access::VertexRead),
        Some(bb(
            XFER,
            A::TRANSFER_WRITE,
            S::VERTEX_ATTRIBUTE_INPUT,
            A::VERTEX_ATTRIBUTE_READ
        ))
    );
    assert_eq!(
        buf.transition(Access::HostRead),
        Some(bb(XFER, A::TRANSFER_WRITE, S::HOST, A::HOST_READ))
    );
    assert_eq!(buf.transition(Access::HostRead), None);
    // WAR after both readers.
    assert_eq!(
        buf.transition(Access::StorageWrite { stages: CS }),
        Some(bb(S::VERTEX_ATTRIBUTE_INPUT | S::HOST, NONE_A, CS, ST_RW))
    );
    // WAW.
    assert_eq!(
        buf.transition(Access::StorageWrite { stages: CS }),
        Some(bb(CS, ST_W, CS, ST_RW))
    );
    // Indirect arguments and index data produced by the same compute pass.
    assert_eq!(
        buf.transition(Access::IndirectRead),
        Some(bb(CS, ST_W, S::DRAW_INDIRECT, A::INDIRECT_COMMAND_READ))
    );
    assert_eq!(
        buf.transition(Access::IndexRead),
        Some(bb(CS, ST_W, S::INDEX_INPUT, A::INDEX_READ))
    );
    // Never-written buffer: reads need nothing.
    let mut fresh = BufferState::default();
    assert_eq!(fresh.transition(Access::UniformRead { stages: VS }), None);
    assert_eq!(
        fresh.transition(Access::TransferWrite),
        Some(bb(VS, NONE_A, XFER, A::TRANSFER_WRITE))
    );
}

#[test]
fn to_vk_structs() {
    let b = ib(
        SubresourceRange::new(1, 2, 3, 4),
        CS,
        ST_W,
        FS,
        SAMPLED,
        L::GENERAL,
        L::SHADER_READ_ONLY_OPTIMAL,
    );
    let v = b.to_vk(vk::Image::null(), vk::ImageAspectFlags::COLOR);
    assert_eq!(
        (v.src_stage_mask, v.src_access_mask, v.dst_stage_mask, v.dst_access_mask),
        (CS, ST_W, FS, SAMPLED)
    );
    assert_eq!((v.old_layout, v.new_layout), (L::GENERAL, L::SHADER_READ_ONLY_OPTIMAL));
    assert_eq!(
        (v.src_queue_family_index, v.dst_queue_family_index),
        (vk::QUEUE_FAMILY_IGNORED, vk::QUEUE_FAMILY_IGNORED)
    );
    let r = v.subresource_range;
    assert_eq!(
        (
            r.aspect_mask,
            r.base_mip_level,
            r.level_count,
            r.base_array_layer,
            r.layer_count
        ),
        (vk::ImageAspectFlags::COLOR, 1, 2, 3, 4)
    );
    let bv = bb(CS, ST_W, FS, ST_R).to_vk(vk::Buffer::null());
    assert_eq!(
        (bv.offset, bv.size, bv.src_queue_family_index),
        (0, vk::WHOLE_SIZE, vk::QUEUE_FAMILY_IGNORED)
    );
    let m = bb(CS, ST_W, FS, ST_R).to_memory_barrier();
    assert_eq!((m.src_stage_mask, m.dst_access_mask), (CS, ST_R));
}

// ---------------------------------------------------------------------------
// Randomized: reference model and synchronization checker
// ---------------------------------------------------------------------------

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        // xorshift64*
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

fn bits(x: u64) -> impl Iterator<Item = u64> {
    (0..64).map(|i| 1u64 << i).filter(move |b| x & b != 0)
}

fn pairs(s: S, a: A) -> impl Iterator<Item = (u64, u64)> {
    let a = a.as_raw();
    bits(s.as_raw()).flat_map(move |sb| bits(a).map(move |ab| (sb, ab)))
}

/// Per-subresource barrier derivation, written independently of `SubState`:
/// the visibility set is kept as explicit (stage bit, access bit) pairs.
#[derive(Clone, Debug)]
struct RefSub {
    layout: L,
    /// (stages to chain from, write bits); `None` while nothing was written.
    write: Option<(S, A)>,
    readers: S,
    visible: HashSet<(u64, u64)>,
}

type Key = (S, A, S, A, L, L);

impl RefSub {
    fn new() -> Self {
        RefSub {
            layout: L::UNDEFINED,
            write: None,
            readers: S::NONE,
            visible: HashSet::new(),
        }
    }

    fn step(&mut self, n: Access, discard: bool, image: bool) -> Option<Key> {
        let (ns, na) = (n.stages(), n.access());
        let nl = if image { n.layout() } else { L::UNDEFINED };
        let write_bits = na & super::WRITE_ACCESS;
        let (ws, wa) = self.write.unwrap_or((S::NONE, A::NONE));
        let key = if nl != self.layout {
            let old = if discard { L::UNDEFINED } else { self.layout };
            let k = (ws | self.readers, wa, ns, na, old, nl);
            self.layout = nl;
            self.write = Some((ns, A::NONE));
            self.readers = S::NONE;
            self.visible = pairs(ns, na).collect();
            Some(k)
        } else if n.is_write() {
            if !self.readers.is_empty() {
                Some((self.readers, A::NONE, ns, na, nl, nl))
            } else {
                self.write.map(|(ws, wa)| (ws, wa, ns, na, nl, nl))
            }
        } else {
            match self.write {
                Some((ws, wa)) if !pairs(ns, na).all(|p| self.visible.contains(&p)) => {
                    self.visible.extend(pairs(ns, na));
                    Some((ws, wa, ns, na, nl, nl))
                }
                _ => None,
            }
        };
        if n.is_write() {
            self.write = Some((ns, write_bits));
            self.readers = S::NONE;
            self.visible.clear();
        } else if !na.is_empty() {
            self.readers |= ns;
        }
        key
    }
}

/// A small model of what synchronization validation checks, per subresource,
/// on explicit stage bits only (no stage expansion): stricter than the layer.
#[derive(Clone, Debug, Default)]
struct Checker {
    layout: L,
    write: Option<CheckWrite>,
    /// stage bit of a read since the last write → stages ordered after it.
    reads: HashMap<u64, S>,
    written: bool,
}

#[derive(Clone, Debug)]
struct CheckWrite {
    stages: S,
    access: A,
    chain: S,
    visible: HashSet<(u64, u64)>,
}

impl Checker {
    fn write_in_src(w: &CheckWrite, s1: S, a1: A) -> bool {
        let available = !w.access.is_empty() && w.stages.intersects(s1) && a1.contains(w.access);
        available || w.chain.intersects(s1)
    }

    fn barrier(&mut self, b: &Key, discard: bool) -> Result<(), String> {
        let &(s1, a1, s2, a2, old, new) = b;
        if old != new {
            if new == L::UNDEFINED {
                return Err("transition to UNDEFINED".into());
            }
            if old != self.layout && old != L::UNDEFINED {
                return Err(format!("old layout {old:?} but subresource is {:?}", self.layout));
            }
            if old == L::UNDEFINED && self.written && !discard {
                return Err("contents discarded by a plain transition".into());
            }
            for (&stage, &chain) in &self.reads {
                if !(S::from_raw(stage) | chain).intersects(s1) {
                    return Err(format!("WAR: layout transition not after read at {stage:#x}"));
                }
            }
            if let Some(w) = &self.write {
                if !Self::write_in_src(w, s1, a1) {
                    return Err(format!("WAW: layout transition not after write {w:?}"));
                }
            }
            self.layout = new;
            self.reads.clear();
            self.write = Some(CheckWrite {
                stages: S::NONE,
                access: A::NONE,
                chain: s2,
                visible: pairs(s2, a2).collect(),
            });
        } else {
            if old != self.layout {
                return Err(format!("barrier layout {old:?} but subresource is {:?}", self.layout));
            }
            if let Some(w) = &mut self.write {
                if Self::write_in_src(w, s1, a1) {
                    w.chain |= s2;
                    w.visible.extend(pairs(s2, a2));
                }
            }
            for (&stage, chain) in self.reads.iter_mut() {
                if (S::from_raw(stage) | *chain).intersects(s1) {
                    *chain |= s2;
                }
            }
        }
        Ok(())
    }

    fn access(&mut self, n: Access, image: bool) -> Result<(), String> {
        if image && n.layout() != self.layout {
            return Err(format!("{n:?} in layout {:?}", self.layout));
        }
        let (ns, na) = (n.stages(), n.access());
        let reads = na & !super::WRITE_ACCESS;
        let writes = na & super::WRITE_ACCESS;
        if let Some(w) = &self.write {
            if let Some(p) = pairs(ns, reads).find(|p| !w.visible.contains(p)) {
                return Err(format!("RAW: {n:?} at {p:x?} after {w:?}"));
            }
        }
        if n.is_write() {
            if !self.reads.is_empty() {
                for (&stage, &chain) in &self.reads {
                    if !chain.contains(ns) {
                        return Err(format!("WAR: {n:?} after read at {stage:#x} (chain {chain:?})"));
                    }
                }
            } else if let Some(w) = &self.write {
                if let Some(p) = pairs(ns, writes).find(|p| !w.visible.contains(p)) {
                    return Err(format!("WAW: {n:?} at {p:x?} after {w:?}"));
                }
                if !w.chain.contains(ns) {
                    return Err(format!("WAW: {n:?} not ordered after {w:?}"));
                }
            }
            self.write = Some(CheckWrite {
                stages: ns,
                access: writes,
                chain: S::NONE,
                visible: HashSet::new(),
            });
            self.reads.clear();
            self.written = true;
        } else {
            for stage in bits(ns.as_raw()) {
                self.reads.insert(stage, S::NONE);
            }
        }
        Ok(())
    }
}

fn random_stages(rng: &mut Rng) -> S {
    let choice = [VS, FS, CS];
    loop {
        let mut s = S::NONE;
        for c in choice {
            if rng.below(2) == 0 {
                s |= c;
            }
        }
        if !s.is_empty() {
            return s;
        }
    }
}

fn random_image_access(rng: &mut Rng, depth: bool) -> Access {
    let st = random_stages(rng);
    if depth {
        match rng.below(6) {
            0 => Access::DepthStencilAttachmentWrite,
            1 => Access::DepthStencilAttachmentRead,
            2 => Access::DepthSampledRead { stages: st },
            3 => Access::SampledRead { stages: st },
            4 => Access::TransferRead,
            _ => Access::TransferWrite,
        }
    } else {
        match rng.below(8) {
            0 => Access::SampledRead { stages: st },
            1 => Access::StorageRead { stages: st },
            2 => Access::StorageWrite { stages: st },
            3 => Access::ColorAttachmentWrite,
            4 => Access::TransferRead,
            5 => Access::TransferWrite,
            6 => Access::HostRead,
            _ => Access::SampledRead { stages: FS },
        }
    }
}

fn random_buffer_access(rng: &mut Rng) -> Access {
    let st = random_stages(rng);
    match rng.below(10) {
        0 => Access::VertexRead,
        1 => Access::IndexRead,
        2 => Access::IndirectRead,
        3 => Access::UniformRead { stages: st },
        4 => Access::StorageRead { stages: st },
        5 => Access::StorageWrite { stages: st },
        6 => Access::TransferRead,
        7 => Access::TransferWrite,
        8 => Access::HostRead,
        _ => Access::SampledRead { stages: st },
    }
}

#[test]
fn random_image_sequences_match_reference_and_are_hazard_free() {
    let (mips, layers) = (4u32, 3u32);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut total_barriers = 0usize;
    let mut total_cells = 0usize;
    for seq in 0..300 {
        let depth = seq % 4 == 3;
        let mut img = ImageState::new(mips, layers);
        let mut reference = vec![RefSub::new(); (mips * layers) as usize];
        let mut checker = vec![Checker::default(); (mips * layers) as usize];
        let idx = |m: u32, l: u32| (m * layers + l) as usize;
        for step in 0..60 {
            let base_mip = rng.below(mips as u64) as u32;
            let mip_count = 1 + rng.below((mips - base_mip) as u64) as u32;
            let base_layer = rng.below(layers as u64) as u32;
            let layer_count = 1 + rng.below((layers - base_layer) as u64) as u32;
            // Bias towards large ranges so that merging has work to do.
            let range = if rng.below(3) == 0 {
                SubresourceRange::all(mips, layers)
            } else {
                SubresourceRange::new(base_mip, mip_count, base_layer, layer_count)
            };
            let next = random_image_access(&mut rng, depth);
            let discard = next.is_write() && rng.below(4) == 0;
            let ctx = format!("seq {seq} step {step}: {range:?} {next:?} discard={discard}");
            let got = if discard {
                img.transition_discard(range, next)
            } else {
                img.transition(range, next)
            };

            // Barriers are disjoint rectangles inside the range.
            let mut per_cell: HashMap<(u32, u32), Key> = HashMap::new();
            for b in &got {
                let r = b.range;
                assert!(r.mip_count > 0 && r.layer_count > 0, "{ctx}: empty {b:?}");
                for m in r.base_mip..r.base_mip + r.mip_count {
                    for l in r.base_layer..r.base_layer + r.layer_count {
                        assert!(range.contains(m, l), "{ctx}: {b:?} outside range");
                        let key = (
                            b.src_stages,
                            b.src_access,
                            b.dst_stages,
                            b.dst_access,
                            b.old_layout,
                            b.new_layout,
                        );
                        assert!(
                            per_cell.insert((m, l), key).is_none(),
                            "{ctx}: overlapping barriers {got:#?}"
                        );
                    }
                }
            }
            total_barriers += got.len();

            for m in range.base_mip..range.base_mip + range.mip_count {
                for l in range.base_layer..range.base_layer + range.layer_count {
                    // What was emitted is hazard-free...
                    let have = per_cell.get(&(m, l)).copied();
                    let c = &mut checker[idx(m, l)];
                    if let Some(k) = have {
                        c.barrier(&k, discard)
                            .unwrap_or_else(|e| panic!("{ctx}: cell ({m},{l}): {e}"));
                    }
                    c.access(next, true)
                        .unwrap_or_else(|e| panic!("{ctx}: cell ({m},{l}): {e}"));
                    // ...and exactly what the per-subresource rules derive.
                    let want = reference[idx(m, l)].step(next, discard, true);
                    assert_eq!(have, want, "{ctx}: cell ({m},{l})");
                    total_cells += want.is_some() as usize;
                }
            }
            for m in 0..mips {
                for l in 0..layers {
                    assert_eq!(img.layout(m, l), reference[idx(m, l)].layout, "{ctx}: layout ({m},{l})");
                }
            }
        }
    }
    // Merging did merge.
    assert!(
        total_barriers * 2 < total_cells,
        "{total_barriers} barriers for {total_cells} cells"
    );
}

#[test]
fn random_buffer_sequences_match_reference_and_are_hazard_free() {
    let mut rng = Rng(0x0123_4567_89AB_CDEF);
    for seq in 0..300 {
        let mut buf = BufferState::new();
        let mut reference = RefSub::new();
        let mut checker = Checker::default();
        for step in 0..60 {
            let next = random_buffer_access(&mut rng);
            let got = buf.transition(next);
            let ctx = format!("seq {seq} step {step}: {next:?}");
            let ul = L::UNDEFINED;
            if let Some(b) = got {
                let k = (b.src_stages, b.src_access, b.dst_stages, b.dst_access, ul, ul);
                checker.barrier(&k, false).unwrap_or_else(|e| panic!("{ctx}: {e}"));
            }
            checker.access(next, false).unwrap_or_else(|e| panic!("{ctx}: {e}"));
            let want = reference.step(next, false, false);
            assert_eq!(
                got.map(|b| (b.src_stages, b.src_access, b.dst_stages, b.dst_access)),
                want.map(|k| (k.0, k.1, k.2, k.3)),
                "{ctx}"
            );
        }
    }
}

/// The checker must itself catch what it is there to catch.
#[test]
fn checker_catches_missing_barriers() {
    let mut c = Checker::default();
    let w = Access::StorageWrite { stages: CS };
    c.barrier(&(NONE_S, NONE_A, CS, ST_RW, L::UNDEFINED, L::GENERAL), false)
        .unwrap();
    c.access(w, true).unwrap();
    // RAW without barrier.
    assert!(c.clone().access(Access::StorageRead { stages: FS }, true).is_err());
    // WAW without barrier.
    assert!(c.clone().access(w, true).is_err());
    // Barrier to the wrong stage.
    let mut c2 = c.clone();
    c2.barrier(&(CS, ST_W, VS, ST_R, L::GENERAL, L::GENERAL), false)
        .unwrap();
    assert!(c2.access(Access::StorageRead { stages: FS }, true).is_err());
    // WAR without barrier.
    let mut c3 = c.clone();
    c3.barrier(&(CS, ST_W, FS, ST_R, L::GENERAL, L::GENERAL), false)
        .unwrap();
    c3.access(Access::StorageRead { stages: FS }, true).unwrap();
    assert!(c3.clone().access(w, true).is_err());
    // Transition that does not wait for the reader.
    assert!(c3
        .clone()
        .barrier(&(CS, ST_W, CS, SAMPLED, L::GENERAL, L::SHADER_READ_ONLY_OPTIMAL), false)
        .is_err());
    // Transition from UNDEFINED without discard.
    assert!(c3
        .barrier(
            &(FS, NONE_A, CS, SAMPLED, L::UNDEFINED, L::SHADER_READ_ONLY_OPTIMAL),
            false
        )
        .is_err());
    // Chaining through a transition's destination stage is accepted.
    let mut c4 = Checker::default();
    c4.barrier(
        &(NONE_S, NONE_A, FS, SAMPLED, L::UNDEFINED, L::SHADER_READ_ONLY_OPTIMAL),
        false,
    )
    .unwrap();
    c4.access(Access::SampledRead { stages: FS }, true).unwrap();
    assert!(c4.clone().access(Access::SampledRead { stages: CS }, true).is_err());
    c4.barrier(
        &(
            FS,
            NONE_A,
            CS,
            SAMPLED,
            L::SHADER_READ_ONLY_OPTIMAL,
            L::SHADER_READ_ONLY_OPTIMAL,
        ),
        false,
    )
    .unwrap();
    c4.access(Access::SampledRead { stages: CS }, true).unwrap();
}

#[test]
fn aliasing_successor_waits_for_everything_pending() {
    // A transient image: mip 0 sampled by the fragment shader, mip 1 written by
    // compute and never read. The next image placed on the same memory must wait
    // for both, and make the unread write available before its transition.
    let mut old = ImageState::new(2, 1);
    old.transition(SubresourceRange::mip(0), Access::ColorAttachmentWrite);
    old.transition(SubresourceRange::mip(0), Access::SampledRead { stages: FS });
    old.transition(SubresourceRange::mip(1), Access::StorageWrite { stages: CS });
    let (stages, access) = old.pending();
    assert_eq!((stages, access), (FS | CS, ST_W));
    let mut new = ImageState::external(1, 1, L::UNDEFINED, stages, access);
    let all = SubresourceRange::all(1, 1);
    assert_eq!(
        new.transition_discard(all, Access::TransferWrite),
        vec![ib(
            all,
            FS | CS,
            ST_W,
            XFER,
            A::TRANSFER_WRITE,
            L::UNDEFINED,
            L::TRANSFER_DST_OPTIMAL
        )]
    );

    let mut buf = BufferState::new();
    buf.transition(Access::StorageWrite { stages: CS });
    buf.transition(Access::IndirectRead);
    let (stages, access) = buf.pending();
    assert_eq!((stages, access), (CS | S::DRAW_INDIRECT, ST_W));
    let mut next = BufferState::external(stages, access);
    assert_eq!(
        next.transition(Access::TransferWrite),
        Some(bb(CS | S::DRAW_INDIRECT, ST_W, XFER, A::TRANSFER_WRITE))
    );
}

#[test]
fn access_free_read_is_not_a_reader() {
    // A custom "read" with no memory access must not turn a later WAW into a
    // WAR dependency chained through a stage that never waited for the write.
    let mut buf = BufferState::new();
    buf.transition(Access::StorageWrite { stages: CS });
    let probe = Access::Custom {
        stages: FS,
        access: NONE_A,
        layout: L::GENERAL,
        write: false,
    };
    assert_eq!(buf.transition(probe), None);
    assert_eq!(
        buf.transition(Access::StorageWrite { stages: CS }),
        Some(bb(CS, ST_W, CS, ST_RW))
    );
}
