//! How a PNG's 8 bits encode the linear image: as they are ([`Encoding::Linear`], glint's
//! default, which keeps the five original scenes' images) or through the sRGB transfer
//! curve ([`Encoding::Srgb`], what image viewers assume, so that a textured scene looks
//! like its textures). EXR is always linear.
//!
//! The sRGB bytes come from a table of 255 f32 thresholds, not from `powf`: a byte is the
//! number of thresholds at or below the value, so it is the same on every machine, in the
//! browser and under any libm. Each threshold is the smallest f32 whose exact sRGB value,
//! times 255, rounds (half up, as [`crate::shared::real::to_u8`]) to that byte or above; a test
//! rebuilds the table from the curve in f64.

use std::fmt;
use std::str::FromStr;

/// The transfer from linear colour to a PNG's bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// Linear values scaled to 8 bits ([`crate::shared::real::to_u8`]).
    #[default]
    Linear,
    /// The sRGB transfer curve (IEC 61966-2-1), then 8 bits; the PNG says so (`sRGB`).
    Srgb,
}

impl Encoding {
    /// The names the scene format and the command line use.
    pub const NAMES: [&'static str; 2] = ["linear", "srgb"];

    /// The name (`linear`, `srgb`).
    pub fn name(self) -> &'static str {
        match self {
            Encoding::Linear => "linear",
            Encoding::Srgb => "srgb",
        }
    }

    /// One linear channel to its byte.
    #[inline]
    pub fn byte(self, x: f32) -> u8 {
        match self {
            Encoding::Linear => crate::shared::real::to_u8(x),
            Encoding::Srgb => to_u8_srgb(x),
        }
    }
}

impl fmt::Display for Encoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An unknown encoding name.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown encoding {0:?}: use \"linear\" or \"srgb\"")]
pub struct UnknownEncoding(pub String);

impl FromStr for Encoding {
    type Err = UnknownEncoding;
    fn from_str(s: &str) -> Result<Encoding, UnknownEncoding> {
        match s {
            "linear" => Ok(Encoding::Linear),
            "srgb" => Ok(Encoding::Srgb),
            _ => Err(UnknownEncoding(s.to_owned())),
        }
    }
}

/// One linear channel to an sRGB byte: NaN and values at or below 0 give 0, at or above
/// the last threshold 255.
#[inline]
pub fn to_u8_srgb(x: f32) -> u8 {
    // `partition_point` counts the thresholds at or below x; NaN compares false: 0.
    SRGB_THRESHOLDS.partition_point(|&t| t <= x) as u8
}

/// `SRGB_THRESHOLDS[k - 1]`: the smallest f32 that encodes to byte k or above.
pub const SRGB_THRESHOLDS: [f32; 255] = [
    f32::from_bits(0x391f22b4), // 1: 0.000151763496
    f32::from_bits(0x39eeb40e), // 2: 0.000455290487
    f32::from_bits(0x3a46eb61), // 3: 0.000758817478
    f32::from_bits(0x3a8b3e5e), // 4: 0.00106234453
    f32::from_bits(0x3ab3070b), // 5: 0.00136587152
    f32::from_bits(0x3adacfb8), // 6: 0.00166939851
    f32::from_bits(0x3b014c33), // 7: 0.00197292562
    f32::from_bits(0x3b153089), // 8: 0.00227645249
    f32::from_bits(0x3b2914df), // 9: 0.00257997937
    f32::from_bits(0x3b3cf936), // 10: 0.00288350647
    f32::from_bits(0x3b50f2d1), // 11: 0.00318830111
    f32::from_bits(0x3b65fb9b), // 12: 0.00350925955
    f32::from_bits(0x3b7c3403), // 13: 0.00384831498
    f32::from_bits(0x3b89d060), // 14: 0.00420574844
    f32::from_bits(0x3b962333), // 15: 0.00458183279
    f32::from_bits(0x3ba314bd), // 16: 0.00497683743
    f32::from_bits(0x3bb0a731), // 17: 0.00539102452
    f32::from_bits(0x3bbedcb7), // 18: 0.0058246511
    f32::from_bits(0x3bcdb76d), // 19: 0.00627796957
    f32::from_bits(0x3bdd3967), // 20: 0.00675122766
    f32::from_bits(0x3bed64af), // 21: 0.00724466844
    f32::from_bits(0x3bfe3b46), // 22: 0.00775853079
    f32::from_bits(0x3c07df91), // 23: 0.00829304848
    f32::from_bits(0x3c10f91b), // 24: 0.00884845387
    f32::from_bits(0x3c1a6b32), // 25: 0.00942497142
    f32::from_bits(0x3c2436c8), // 26: 0.0100228265
    f32::from_bits(0x3c2e5cc7), // 27: 0.010642237
    f32::from_bits(0x3c38de1a), // 28: 0.0112834219
    f32::from_bits(0x3c43bba4), // 29: 0.0119465925
    f32::from_bits(0x3c4ef648), // 30: 0.0126319602
    f32::from_bits(0x3c5a8ee4), // 31: 0.0133397318
    f32::from_bits(0x3c668654), // 32: 0.0140701123
    f32::from_bits(0x3c72dd71), // 33: 0.0148233036
    f32::from_bits(0x3c7f950f), // 34: 0.0155995032
    f32::from_bits(0x3c865702), // 35: 0.0163989104
    f32::from_bits(0x3c8d148f), // 36: 0.0172217172
    f32::from_bits(0x3c940396), // 37: 0.0180681162
    f32::from_bits(0x3c9b247c), // 38: 0.0189382955
    f32::from_bits(0x3ca277a6), // 39: 0.0198324434
    f32::from_bits(0x3ca9fd78), // 40: 0.0207507461
    f32::from_bits(0x3cb1b653), // 41: 0.0216933843
    f32::from_bits(0x3cb9a298), // 42: 0.0226605386
    f32::from_bits(0x3cc1c2a9), // 43: 0.0236523915
    f32::from_bits(0x3cca16e3), // 44: 0.0246691164
    f32::from_bits(0x3cd29fa4), // 45: 0.0257108882
    f32::from_bits(0x3cdb5d4b), // 46: 0.026777884
    f32::from_bits(0x3ce45032), // 47: 0.0278702714
    f32::from_bits(0x3ced78b5), // 48: 0.0289882217
    f32::from_bits(0x3cf6d72e), // 49: 0.0301319025
    f32::from_bits(0x3d0035fc), // 50: 0.0313014835
    f32::from_bits(0x3d051bb4), // 51: 0.0324971229
    f32::from_bits(0x3d0a1cec), // 52: 0.0337189883
    f32::from_bits(0x3d0f39d0), // 53: 0.0349672437
    f32::from_bits(0x3d14728a), // 54: 0.0362420455
    f32::from_bits(0x3d19c745), // 55: 0.0375435539
    f32::from_bits(0x3d1f382c), // 56: 0.038871929
    f32::from_bits(0x3d24c567), // 57: 0.04022732
    f32::from_bits(0x3d2a6f22), // 58: 0.0416098908
    f32::from_bits(0x3d303584), // 59: 0.0430197865
    f32::from_bits(0x3d3618b7), // 60: 0.0444571637
    f32::from_bits(0x3d3c18e4), // 61: 0.045922175
    f32::from_bits(0x3d423632), // 62: 0.0474149659
    f32::from_bits(0x3d4870ca), // 63: 0.048935689
    f32::from_bits(0x3d4ec8d2), // 64: 0.0504844859
    f32::from_bits(0x3d553e73), // 65: 0.0520615093
    f32::from_bits(0x3d5bd1d3), // 66: 0.0536669008
    f32::from_bits(0x3d628318), // 67: 0.055300802
    f32::from_bits(0x3d69526a), // 68: 0.0569633618
    f32::from_bits(0x3d703fee), // 69: 0.0586547181
    f32::from_bits(0x3d774bca), // 70: 0.0603750125
    f32::from_bits(0x3d7e7624), // 71: 0.0621243864
    f32::from_bits(0x3d82df90), // 72: 0.0639029741
    f32::from_bits(0x3d869372), // 73: 0.0657109171
    f32::from_bits(0x3d8a56cb), // 74: 0.067548357
    f32::from_bits(0x3d8e29ab), // 75: 0.0694154128
    f32::from_bits(0x3d920c27), // 76: 0.0713122413
    f32::from_bits(0x3d95fe4f), // 77: 0.0732389614
    f32::from_bits(0x3d9a0035), // 78: 0.0751957074
    f32::from_bits(0x3d9e11ec), // 79: 0.0771826208
    f32::from_bits(0x3da23384), // 80: 0.0791998208
    f32::from_bits(0x3da66510), // 81: 0.0812474489
    f32::from_bits(0x3daaa6a0), // 82: 0.0833256245
    f32::from_bits(0x3daef847), // 83: 0.085434489
    f32::from_bits(0x3db35a15), // 84: 0.0875741616
    f32::from_bits(0x3db7cc1b), // 85: 0.089744769
    f32::from_bits(0x3dbc4e6b), // 86: 0.0919464454
    f32::from_bits(0x3dc0e114), // 87: 0.0941793025
    f32::from_bits(0x3dc58429), // 88: 0.0964434817
    f32::from_bits(0x3dca37b9), // 89: 0.098739095
    f32::from_bits(0x3dcefbd6), // 90: 0.101066276
    f32::from_bits(0x3dd3d08f), // 91: 0.103425138
    f32::from_bits(0x3dd8b5f5), // 92: 0.105815805
    f32::from_bits(0x3dddac19), // 93: 0.108238406
    f32::from_bits(0x3de2b30a), // 94: 0.110693052
    f32::from_bits(0x3de7cad9), // 95: 0.11317987
    f32::from_bits(0x3decf395), // 96: 0.115698971
    f32::from_bits(0x3df22d50), // 97: 0.118250489
    f32::from_bits(0x3df77817), // 98: 0.120834522
    f32::from_bits(0x3dfcd3fc), // 99: 0.123451203
    f32::from_bits(0x3e012087), // 100: 0.126100644
    f32::from_bits(0x3e03dfae), // 101: 0.128782958
    f32::from_bits(0x3e06a77b), // 102: 0.131498262
    f32::from_bits(0x3e0977f6), // 103: 0.134246677
    f32::from_bits(0x3e0c5126), // 104: 0.137028307
    f32::from_bits(0x3e0f3314), // 105: 0.139843285
    f32::from_bits(0x3e121dc5), // 106: 0.142691687
    f32::from_bits(0x3e151143), // 107: 0.145573661
    f32::from_bits(0x3e180d95), // 108: 0.148489311
    f32::from_bits(0x3e1b12c2), // 109: 0.151438743
    f32::from_bits(0x3e1e20d1), // 110: 0.15442206
    f32::from_bits(0x3e2137cb), // 111: 0.157439396
    f32::from_bits(0x3e2457b6), // 112: 0.160490841
    f32::from_bits(0x3e278099), // 113: 0.163576499
    f32::from_bits(0x3e2ab27d), // 114: 0.166696504
    f32::from_bits(0x3e2ded68), // 115: 0.169850945
    f32::from_bits(0x3e313161), // 116: 0.173039928
    f32::from_bits(0x3e347e70), // 117: 0.176263571
    f32::from_bits(0x3e37d49c), // 118: 0.179521978
    f32::from_bits(0x3e3b33ec), // 119: 0.182815254
    f32::from_bits(0x3e3e9c67), // 120: 0.186143503
    f32::from_bits(0x3e420e15), // 121: 0.189506844
    f32::from_bits(0x3e4588fb), // 122: 0.192905352
    f32::from_bits(0x3e490d22), // 123: 0.19633916
    f32::from_bits(0x3e4c9a90), // 124: 0.199808359
    f32::from_bits(0x3e50314c), // 125: 0.203313053
    f32::from_bits(0x3e53d15d), // 126: 0.206853345
    f32::from_bits(0x3e577aca), // 127: 0.210429341
    f32::from_bits(0x3e5b2d9a), // 128: 0.214041144
    f32::from_bits(0x3e5ee9d4), // 129: 0.217688859
    f32::from_bits(0x3e62af7e), // 130: 0.221372575
    f32::from_bits(0x3e667e9f), // 131: 0.225092396
    f32::from_bits(0x3e6a573e), // 132: 0.228848428
    f32::from_bits(0x3e6e3962), // 133: 0.232640773
    f32::from_bits(0x3e722511), // 134: 0.236469522
    f32::from_bits(0x3e761a52), // 135: 0.240334779
    f32::from_bits(0x3e7a192c), // 136: 0.244236648
    f32::from_bits(0x3e7e21a5), // 137: 0.248175219
    f32::from_bits(0x3e8119e2), // 138: 0.252150595
    f32::from_bits(0x3e8327c7), // 139: 0.256162852
    f32::from_bits(0x3e853a86), // 140: 0.260212123
    f32::from_bits(0x3e875222), // 141: 0.264298499
    f32::from_bits(0x3e896e9d), // 142: 0.268422037
    f32::from_bits(0x3e8b8ffc), // 143: 0.272582889
    f32::from_bits(0x3e8db641), // 144: 0.276781112
    f32::from_bits(0x3e8fe170), // 145: 0.281016827
    f32::from_bits(0x3e92118b), // 146: 0.285290092
    f32::from_bits(0x3e944696), // 147: 0.289601028
    f32::from_bits(0x3e968095), // 148: 0.293949753
    f32::from_bits(0x3e98bf89), // 149: 0.298336297
    f32::from_bits(0x3e9b0377), // 150: 0.30276081
    f32::from_bits(0x3e9d4c62), // 151: 0.30722338
    f32::from_bits(0x3e9f9a4c), // 152: 0.311724067
    f32::from_bits(0x3ea1ed38), // 153: 0.31626296
    f32::from_bits(0x3ea4452b), // 154: 0.32084021
    f32::from_bits(0x3ea6a226), // 155: 0.325455844
    f32::from_bits(0x3ea9042e), // 156: 0.330110013
    f32::from_bits(0x3eab6b44), // 157: 0.334802747
    f32::from_bits(0x3eadd76d), // 158: 0.339534193
    f32::from_bits(0x3eb048aa), // 159: 0.344304383
    f32::from_bits(0x3eb2bf00), // 160: 0.349113464
    f32::from_bits(0x3eb53a71), // 161: 0.353961498
    f32::from_bits(0x3eb7bb00), // 162: 0.358848572
    f32::from_bits(0x3eba40b1), // 163: 0.363774806
    f32::from_bits(0x3ebccb85), // 164: 0.368740231
    f32::from_bits(0x3ebf5b81), // 165: 0.373744994
    f32::from_bits(0x3ec1f0a7), // 166: 0.378789157
    f32::from_bits(0x3ec48af9), // 167: 0.383872777
    f32::from_bits(0x3ec72a7c), // 168: 0.388996005
    f32::from_bits(0x3ec9cf32), // 169: 0.3941589
    f32::from_bits(0x3ecc791e), // 170: 0.399361551
    f32::from_bits(0x3ecf2842), // 171: 0.404604018
    f32::from_bits(0x3ed1dca2), // 172: 0.40988642
    f32::from_bits(0x3ed49641), // 173: 0.415208846
    f32::from_bits(0x3ed75521), // 174: 0.420571357
    f32::from_bits(0x3eda1946), // 175: 0.425974071
    f32::from_bits(0x3edce2b2), // 176: 0.431417048
    f32::from_bits(0x3edfb168), // 177: 0.436900377
    f32::from_bits(0x3ee2856a), // 178: 0.442424119
    f32::from_bits(0x3ee55ebd), // 179: 0.447988421
    f32::from_bits(0x3ee83d63), // 180: 0.453593343
    f32::from_bits(0x3eeb215d), // 181: 0.459238917
    f32::from_bits(0x3eee0ab1), // 182: 0.464925319
    f32::from_bits(0x3ef0f95f), // 183: 0.47065255
    f32::from_bits(0x3ef3ed6b), // 184: 0.47642073
    f32::from_bits(0x3ef6e6d8), // 185: 0.482229948
    f32::from_bits(0x3ef9e5a8), // 186: 0.488080263
    f32::from_bits(0x3efce9de), // 187: 0.493971765
    f32::from_bits(0x3efff37e), // 188: 0.499904573
    f32::from_bits(0x3f018145), // 189: 0.505878747
    f32::from_bits(0x3f030b82), // 190: 0.511894345
    f32::from_bits(0x3f049877), // 191: 0.517951429
    f32::from_bits(0x3f062827), // 192: 0.524050176
    f32::from_bits(0x3f07ba92), // 193: 0.530190587
    f32::from_bits(0x3f094fb9), // 194: 0.536372721
    f32::from_bits(0x3f0ae79f), // 195: 0.542596757
    f32::from_bits(0x3f0c8244), // 196: 0.548862696
    f32::from_bits(0x3f0e1faa), // 197: 0.555170655
    f32::from_bits(0x3f0fbfd2), // 198: 0.561520696
    f32::from_bits(0x3f1162be), // 199: 0.567912936
    f32::from_bits(0x3f13086e), // 200: 0.574347377
    f32::from_bits(0x3f14b0e4), // 201: 0.580824137
    f32::from_bits(0x3f165c22), // 202: 0.587343335
    f32::from_bits(0x3f180a29), // 203: 0.593905032
    f32::from_bits(0x3f19bafa), // 204: 0.600509286
    f32::from_bits(0x3f1b6e96), // 205: 0.607156157
    f32::from_bits(0x3f1d24ff), // 206: 0.613845766
    f32::from_bits(0x3f1ede36), // 207: 0.62057817
    f32::from_bits(0x3f209a3c), // 208: 0.62735343
    f32::from_bits(0x3f225913), // 209: 0.634171665
    f32::from_bits(0x3f241abc), // 210: 0.641032934
    f32::from_bits(0x3f25df38), // 211: 0.647937298
    f32::from_bits(0x3f27a689), // 212: 0.654884875
    f32::from_bits(0x3f2970af), // 213: 0.661875665
    f32::from_bits(0x3f2b3dad), // 214: 0.668909848
    f32::from_bits(0x3f2d0d83), // 215: 0.675987422
    f32::from_bits(0x3f2ee032), // 216: 0.683108449
    f32::from_bits(0x3f30b5bd), // 217: 0.690273106
    f32::from_bits(0x3f328e24), // 218: 0.697481394
    f32::from_bits(0x3f346968), // 219: 0.704733372
    f32::from_bits(0x3f36478b), // 220: 0.712029159
    f32::from_bits(0x3f38288f), // 221: 0.719368875
    f32::from_bits(0x3f3a0c73), // 222: 0.72675246
    f32::from_bits(0x3f3bf33a), // 223: 0.734180093
    f32::from_bits(0x3f3ddce5), // 224: 0.741651833
    f32::from_bits(0x3f3fc975), // 225: 0.74916774
    f32::from_bits(0x3f41b8eb), // 226: 0.756727874
    f32::from_bits(0x3f43ab48), // 227: 0.764332294
    f32::from_bits(0x3f45a08f), // 228: 0.77198118
    f32::from_bits(0x3f4798bf), // 229: 0.77967447
    f32::from_bits(0x3f4993db), // 230: 0.787412345
    f32::from_bits(0x3f4b91e3), // 231: 0.795194805
    f32::from_bits(0x3f4d92d8), // 232: 0.803021908
    f32::from_bits(0x3f4f96bd), // 233: 0.810893834
    f32::from_bits(0x3f519d92), // 234: 0.818810582
    f32::from_bits(0x3f53a758), // 235: 0.826772213
    f32::from_bits(0x3f55b411), // 236: 0.834778845
    f32::from_bits(0x3f57c3be), // 237: 0.842830539
    f32::from_bits(0x3f59d65f), // 238: 0.850927293
    f32::from_bits(0x3f5bebf7), // 239: 0.859069288
    f32::from_bits(0x3f5e0486), // 240: 0.867256522
    f32::from_bits(0x3f60200e), // 241: 0.875489116
    f32::from_bits(0x3f623e90), // 242: 0.883767128
    f32::from_bits(0x3f64600c), // 243: 0.892090559
    f32::from_bits(0x3f668485), // 244: 0.900459588
    f32::from_bits(0x3f68abfb), // 245: 0.908874214
    f32::from_bits(0x3f6ad670), // 246: 0.917334557
    f32::from_bits(0x3f6d03e5), // 247: 0.925840676
    f32::from_bits(0x3f6f345a), // 248: 0.934392571
    f32::from_bits(0x3f7167d2), // 249: 0.942990422
    f32::from_bits(0x3f739e4d), // 250: 0.951634228
    f32::from_bits(0x3f75d7cc), // 251: 0.960324049
    f32::from_bits(0x3f781451), // 252: 0.969060004
    f32::from_bits(0x3f7a53dd), // 253: 0.977842152
    f32::from_bits(0x3f7c9671), // 254: 0.986670554
    f32::from_bits(0x3f7edc0e), // 255: 0.995545268
];

#[cfg(test)]
mod tests {
    use super::*;

    /// The sRGB curve in f64 (IEC 61966-2-1).
    fn encode(l: f64) -> f64 {
        if l <= 0.0031308 {
            l * 12.92
        } else {
            1.055 * l.powf(1.0 / 2.4) - 0.055
        }
    }

    fn byte_f64(x: f32) -> u8 {
        (encode((x as f64).clamp(0.0, 1.0)) * 255.0 + 0.5).floor() as u8
    }

    #[test]
    fn thresholds_are_the_curve_in_f64() {
        for (i, &t) in SRGB_THRESHOLDS.iter().enumerate() {
            let k = i as u8 + 1;
            let below = f32::from_bits(t.to_bits() - 1);
            assert!(
                byte_f64(t) >= k && byte_f64(below) < k,
                "threshold {k}: {t:e}"
            );
        }
    }

    #[test]
    fn bytes_are_the_curve_in_f64_and_specials_are_clamped() {
        let mut x = 0.0f32;
        while x <= 1.0 {
            assert_eq!(to_u8_srgb(x), byte_f64(x), "{x:e}");
            x = f32::from_bits(x.to_bits() + 997);
        }
        for (x, b) in [
            (f32::NAN, 0),
            (-1.0, 0),
            (0.0, 0),
            (1.0, 255),
            (7.0, 255),
            (f32::INFINITY, 255),
        ] {
            assert_eq!(to_u8_srgb(x), b, "{x}");
        }
        // The twin: the linear bytes are not the curve's.
        assert_ne!(Encoding::Linear.byte(0.2), byte_f64(0.2));
        assert_eq!(Encoding::Srgb.byte(0.2), byte_f64(0.2));
    }

    #[test]
    fn names_round_trip() {
        for n in Encoding::NAMES {
            assert_eq!(n.parse::<Encoding>().unwrap().name(), n);
        }
        assert!("sRGB".parse::<Encoding>().is_err());
    }
}
