//! The tests' seeded random streams: one implementation of each generator the tests use. A test
//! whose tolerances were measured on a stream keeps that stream, so the generators stay as they
//! were measured: Knuth's MMIX linear congruential generator, Marsaglia's xorshift64 (13, 7, 17)
//! and xorshift64* (Vigna's multiplied output). Nothing in the library draws from these.

/// 53 high bits as a float in [0, 1).
fn unit_f64(bits: u64) -> f64 {
    (bits >> 11) as f64 / (1u64 << 53) as f64
}

/// 24 high bits as a float in [0, 1): exact in f32.
fn unit_f32(bits: u64) -> f32 {
    ((bits >> 40) as f64 / (1u64 << 24) as f64) as f32
}

/// Knuth's MMIX linear congruential generator; the seed is the first state.
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0
    }
    pub fn next_f64(&mut self) -> f64 {
        unit_f64(self.next_u64())
    }
    pub fn next_f32(&mut self) -> f32 {
        unit_f32(self.next_u64())
    }
}

/// Marsaglia's xorshift64 with shifts (13, 7, 17); the seed must not be 0.
pub struct XorShift(pub u64);

impl XorShift {
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    pub fn next_f64(&mut self) -> f64 {
        unit_f64(self.next_u64())
    }
    pub fn next_f32(&mut self) -> f32 {
        unit_f32(self.next_u64())
    }
}

/// xorshift64*: shifts (12, 25, 27) and a multiplied output; the seed must not be 0.
pub struct XorShiftStar(pub u64);

impl XorShiftStar {
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
}
