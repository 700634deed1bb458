// furnace-gpu: twin of furnace-brdf's `dielectric` module — the exact unpolarised Fresnel
// reflectance, smooth / rough (Walter et al. 2007) / thin-walled (smooth or rough) dielectric interfaces and the
// glTF transmissive mixture (`Transmissive`). Composed only for scenes with a transmissive
// material. Requires brdf.wgsl (its GGX helpers and BsdfParams functions) before it.
//
// The local frame's z is the outward normal (the side of index 1); wo may be on either side.

const DIELECTRIC_SMOOTH: u32 = 0u;
const DIELECTRIC_ROUGH: u32 = 1u;
const DIELECTRIC_THIN: u32 = 2u;
const DIELECTRIC_ROUGH_THIN: u32 = 3u;
// `dielectric::ETA_MIN`, `ETA_MAX`, `ONE_BELOW`.
const DIELECTRIC_ETA_MIN: f32 = 1e-2;
const DIELECTRIC_ETA_MAX: f32 = 1e2;
const DIELECTRIC_ONE_BELOW: f32 = 0.99999994;

// `dielectric::Fresnel`.
struct Fresnel {
    reflectance: f32,
    cos_t: f32,
    eta_it: f32,
    eta_ti: f32,
}

// `fresnel_dielectric`: exact unpolarised R for cos_i to the normal (> 0 from outside).
fn fresnel_dielectric(cos_i: f32, eta: f32) -> Fresnel {
    let outside = cos_i >= 0.0;
    var eta_it = 1.0 / eta;
    var eta_ti = eta;
    if outside {
        eta_it = eta;
        eta_ti = 1.0 / eta;
    }
    if eta == 1.0 {
        return Fresnel(0.0, -cos_i, eta_it, eta_ti);
    }
    let ci = min(abs(cos_i), 1.0);
    let cos_t2 = 1.0 - eta_ti * eta_ti * (1.0 - ci * ci);
    if !(cos_t2 > 0.0) {
        return Fresnel(1.0, 0.0, eta_it, eta_ti);
    }
    let ct = sqrt(cos_t2);
    let rs = (ci - eta_it * ct) / (ci + eta_it * ct);
    let rp = (eta_it * ci - ct) / (eta_it * ci + ct);
    let r = brdf_clamp(0.5 * (rs * rs + rp * rp), 0.0, 1.0);
    return Fresnel(r, select(ct, -ct, outside), eta_it, eta_ti);
}

// `thin_reflectance`: R′ = 2R/(1 + R).
fn thin_reflectance(cos_i: f32, eta: f32) -> f32 {
    let r = fresnel_dielectric(abs(cos_i), eta).reflectance;
    return 2.0 * r / (1.0 + r);
}

// `Dielectric` (α already clamped for rough interfaces). The film's fields (weight 0: none)
// are read only by the IRIDESCENCE code.
struct Dielectric {
    eta: f32,
    alpha: f32,
    iface: u32,
    height_correlated: u32,
    tint: vec3<f32>,
    film_factor: f32,
    film_ior: f32,
    film_thickness: f32,
}

// `Dielectric::new`.
fn dielectric_new(eta_in: f32, alpha: f32, thin_walled: bool, height_correlated: bool,
                  tint: vec3<f32>) -> Dielectric {
    let eta = brdf_sanitize(eta_in, DIELECTRIC_ETA_MIN, DIELECTRIC_ETA_MAX, 1.5);
    let rough = alpha >= BSDF_ALPHA_MIN && eta != 1.0;
    var iface = DIELECTRIC_SMOOTH;
    if thin_walled && rough {
        iface = DIELECTRIC_ROUGH_THIN;
    } else if thin_walled {
        iface = DIELECTRIC_THIN;
    } else if rough {
        iface = DIELECTRIC_ROUGH;
    }
    let a = brdf_sanitize(alpha, BSDF_ALPHA_MIN, 1.0, 1.0);
    return Dielectric(eta, a, iface, select(0u, 1u, height_correlated), brdf_clamp_rgb(tint, 1.0), 0.0, 0.0, 0.0);
}

// #if IRIDESCENCE
// `Dielectric::with_film`.
fn dielectric_with_film(d: Dielectric, factor: f32, ior: f32, thickness: f32) -> Dielectric {
    var r = d;
    let i = brdf_sanitize(factor, 0.0, 1.0, 0.0);
    if i > 0.0 && d.eta != 1.0 {
        r.film_factor = i;
        r.film_ior = brdf_sanitize(ior, 0.01, 100.0, 1.3);
        r.film_thickness = brdf_sanitize(thickness, 0.0, 1.0e6, 0.0);
    }
    return r;
}

// The film's reflectance over the interface's own F0 at the outside cosine `c_out`.
fn dielectric_film(d: Dielectric, c_out: f32) -> vec3<f32> {
    let r = (d.eta - 1.0) / (d.eta + 1.0);
    let f0 = r * r;
    return brdf_film_fresnel(d.film_ior, d.film_thickness, vec3<f32>(f0), c_out);
}
// #endif

// `Dielectric::reflectance`: per channel, the exact R without a film.
fn dielectric_reflectance(d: Dielectric, fr: Fresnel, cos_i: f32) -> vec3<f32> {
    // #if IRIDESCENCE
    if d.film_factor > 0.0 {
        if fr.cos_t == 0.0 { return vec3<f32>(1.0); }
        var c_out = abs(fr.cos_t);
        if cos_i >= 0.0 { c_out = min(cos_i, 1.0); }
        return (1.0 - d.film_factor) * fr.reflectance + d.film_factor * dielectric_film(d, c_out);
    }
    // #endif
    return vec3<f32>(fr.reflectance);
}

// `Dielectric::thin_reflectance_rgb`.
fn dielectric_thin_reflectance(d: Dielectric, cos_i: f32) -> vec3<f32> {
    let r = thin_reflectance(cos_i, d.eta);
    // #if IRIDESCENCE
    if d.film_factor > 0.0 {
        return (1.0 - d.film_factor) * r + d.film_factor * dielectric_film(d, min(abs(cos_i), 1.0));
    }
    // #endif
    return vec3<f32>(r);
}

// `dielectric::ScatterSample` (valid == false is `None`).
struct ScatterSample {
    wi: vec3<f32>,
    pdf: f32,
    weight: vec3<f32>,
    rest: f32,
    delta: bool,
    transmitted: bool,
    valid: bool,
}

fn scatter_none() -> ScatterSample {
    return ScatterSample(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, false, false, false);
}

// `dielectric::rescale`.
fn dielectric_rescale(uc: f32, p: f32, taken: bool) -> f32 {
    var r: f32;
    if taken {
        r = uc / p;
    } else {
        r = (uc - p) / (1.0 - p);
    }
    if brdf_is_finite(r) {
        return brdf_clamp(r, 0.0, DIELECTRIC_ONE_BELOW);
    }
    return 0.0;
}

// `Dielectric::g2_over_cos_o`.
fn dielectric_g2_over_cos_o(d: Dielectric, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let zo = abs(wo.z);
    let zi = abs(wi.z);
    let ao = brdf_ggx_a(brdf_ggx_isotropic(d.alpha), wo);
    let ai = brdf_ggx_a(brdf_ggx_isotropic(d.alpha), wi);
    var r: f32;
    if d.height_correlated != 0u {
        r = 2.0 * zi / (ao * zi + ai * zo);
    } else {
        r = 2.0 / (zo + ao) * (2.0 * zi / (zi + ai));
    }
    if brdf_is_finite(r) {
        return r;
    }
    return 0.0;
}

// `Dielectric::g2_over_g1`: G2(wo, wi)/G1(wo), 0 where G1 is.
fn dielectric_g2_over_g1(d: Dielectric, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let g1o = brdf_ggx_g1(brdf_ggx_isotropic(d.alpha), wo);
    let g = dielectric_g2_over_cos_o(d, wo, wi) * abs(wo.z);
    if g1o > 0.0 {
        return g / g1o;
    }
    return 0.0;
}

// `Dielectric::microfacet`: h (xyz) and validity; the cosines and the lobe are recomputed.
struct Microfacet {
    h: vec3<f32>,
    cos_oh: f32,
    cos_ih: f32,
    eta_it: f32,
    reflect: bool,
    valid: bool,
}

fn dielectric_microfacet(d: Dielectric, wo: vec3<f32>, wi: vec3<f32>) -> Microfacet {
    var m = Microfacet(vec3<f32>(0.0), 0.0, 0.0, 1.0, false, false);
    let zo = wo.z;
    let zi = wi.z;
    if zo == 0.0 || zi == 0.0 || !brdf_is_finite(zo) || !brdf_is_finite(zi) {
        return m;
    }
    let reflect = (zo > 0.0) == (zi > 0.0);
    var eta_it = 1.0 / d.eta;
    if zo > 0.0 {
        eta_it = d.eta;
    }
    var h = wo + wi;
    if !reflect {
        h = wo + wi * eta_it;
    }
    h = brdf_normalize_or(h, vec3<f32>(0.0));
    if all(h == vec3<f32>(0.0)) {
        return m;
    }
    if h.z < 0.0 {
        h = -h;
    }
    let cos_oh = brdf_dot(wo, h);
    let cos_ih = brdf_dot(wi, h);
    if !(cos_oh * zo > 0.0 && cos_ih * zi > 0.0) {
        return m;
    }
    return Microfacet(h, cos_oh, cos_ih, eta_it, reflect, true);
}

// `!Dielectric::is_delta`: a rough interface or a rough sheet.
fn dielectric_is_rough(d: Dielectric) -> bool {
    return d.iface == DIELECTRIC_ROUGH || d.iface == DIELECTRIC_ROUGH_THIN;
}

// `Dielectric::sheet_microfacet`: the half vector of wo and wi mirrored to wo's side, turned up
// (xyz), and wo·h (w); w = 0 where the BSDF is 0. `transmitted`: wi is on the other side.
fn dielectric_sheet_microfacet(wo: vec3<f32>, wi: vec3<f32>) -> vec4<f32> {
    let zo = wo.z;
    let zi = wi.z;
    if zo == 0.0 || zi == 0.0 || !brdf_is_finite(zo) || !brdf_is_finite(zi) {
        return vec4<f32>(0.0);
    }
    var wr = wi;
    if (zo > 0.0) != (zi > 0.0) {
        wr = vec3<f32>(wi.x, wi.y, -wi.z);
    }
    var h = brdf_normalize_or(wo + wr, vec3<f32>(0.0));
    if all(h == vec3<f32>(0.0)) {
        return vec4<f32>(0.0);
    }
    if h.z < 0.0 {
        h = -h;
    }
    let cos_oh = brdf_dot(wo, h);
    if !(cos_oh * zo > 0.0 && brdf_dot(wr, h) * zo > 0.0) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(h, cos_oh);
}

// `Dielectric::eval` of a rough sheet: the GGX reflection weighted R′, its mirror image T′·tint.
fn dielectric_sheet_eval(d: Dielectric, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let m = dielectric_sheet_microfacet(wo, wi);
    if m.w == 0.0 {
        return vec3<f32>(0.0);
    }
    let rgb = dielectric_thin_reflectance(d, m.w);
    let f = brdf_ggx_d(brdf_ggx_isotropic(d.alpha), m.xyz) * dielectric_g2_over_cos_o(d, wo, wi) * 0.25;
    if (wo.z > 0.0) != (wi.z > 0.0) {
        return d.tint * ((1.0 - brdf_max_element(rgb)) * f);
    }
    return rgb * f;
}

// `Dielectric::pdf` of a rough sheet: visible normals of wo's side over 4|wo·h|, times the choice.
fn dielectric_sheet_pdf(d: Dielectric, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let m = dielectric_sheet_microfacet(wo, wi);
    if m.w == 0.0 {
        return 0.0;
    }
    let p = brdf_max_element(dielectric_thin_reflectance(d, m.w));
    var pdf = 2.0 / (abs(wo.z) + brdf_ggx_a(brdf_ggx_isotropic(d.alpha), wo)) * brdf_ggx_d(brdf_ggx_isotropic(d.alpha), m.xyz) * 0.25;
    if (wo.z > 0.0) != (wi.z > 0.0) {
        pdf *= 1.0 - p;
    } else {
        pdf *= p;
    }
    if brdf_is_finite(pdf) {
        return pdf;
    }
    return 0.0;
}

// `Dielectric::sample` of a rough sheet: a visible normal of wo's side, then reflection or its
// mirror image through the sheet by R′ there.
fn dielectric_sheet_sample(d: Dielectric, wo: vec3<f32>, uc: f32, u: vec2<f32>) -> ScatterSample {
    let flip = select(-1.0, 1.0, wo.z > 0.0);
    let h = brdf_ggx_sample_vndf_caps(brdf_ggx_isotropic(d.alpha), wo * flip, u) * flip;
    let cos_oh = brdf_dot(wo, h);
    let r = brdf_reflect(wo, h);
    if !(cos_oh > 0.0) || !(r.z * flip > 0.0) {
        return scatter_none();
    }
    let rgb = dielectric_thin_reflectance(d, cos_oh);
    let p = brdf_max_element(rgb);
    let transmitted = !(uc < p);
    var wi = r;
    if transmitted {
        wi = vec3<f32>(r.x, r.y, -r.z);
    }
    wi = brdf_normalize_or(wi, vec3<f32>(0.0));
    let pdf = dielectric_sheet_pdf(d, wo, wi);
    if !(pdf > 0.0) {
        return scatter_none();
    }
    let weight = dielectric_g2_over_g1(d, wo, wi);
    var w = vec3<f32>(weight);
    if transmitted {
        w = d.tint * weight;
    }
    // #if IRIDESCENCE
    if !transmitted && d.film_factor > 0.0 { w = rgb * (weight / p); }
    // #endif
    return ScatterSample(wi, pdf, w, dielectric_rescale(uc, p, !transmitted), false, transmitted, true);
}

// `Dielectric::eval`: BSDF × |cos θi| (0 for delta interfaces).
fn dielectric_eval(d: Dielectric, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if d.iface == DIELECTRIC_ROUGH_THIN {
        return dielectric_sheet_eval(d, wo, wi);
    }
    if d.iface != DIELECTRIC_ROUGH {
        return vec3<f32>(0.0);
    }
    let m = dielectric_microfacet(d, wo, wi);
    if !m.valid {
        return vec3<f32>(0.0);
    }
    let dd = brdf_ggx_d(brdf_ggx_isotropic(d.alpha), m.h);
    let fr = fresnel_dielectric(m.cos_oh, d.eta);
    let r = dielectric_reflectance(d, fr, m.cos_oh);
    let g = dielectric_g2_over_cos_o(d, wo, wi);
    if m.reflect {
        return r * (dd * g * 0.25);
    }
    let den = m.cos_oh + m.eta_it * m.cos_ih;
    let f = abs(m.cos_oh * m.cos_ih) * (1.0 - brdf_max_element(r)) * dd * g / (den * den);
    if brdf_is_finite(f) {
        return d.tint * f;
    }
    return vec3<f32>(0.0);
}

// `Dielectric::pdf`.
fn dielectric_pdf(d: Dielectric, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if d.iface == DIELECTRIC_ROUGH_THIN {
        return dielectric_sheet_pdf(d, wo, wi);
    }
    if d.iface != DIELECTRIC_ROUGH {
        return 0.0;
    }
    let m = dielectric_microfacet(d, wo, wi);
    if !m.valid {
        return 0.0;
    }
    let fr = fresnel_dielectric(m.cos_oh, d.eta);
    let p_reflect = brdf_max_element(dielectric_reflectance(d, fr, m.cos_oh));
    let dv = 2.0 / (abs(wo.z) + brdf_ggx_a(brdf_ggx_isotropic(d.alpha), wo)) * brdf_ggx_d(brdf_ggx_isotropic(d.alpha), m.h);
    var pdf: f32;
    if m.reflect {
        pdf = dv * p_reflect * 0.25;
    } else {
        let den = m.cos_oh + m.eta_it * m.cos_ih;
        pdf = dv * abs(m.cos_oh) * (1.0 - p_reflect) * (m.eta_it * m.eta_it * abs(m.cos_ih) / (den * den));
    }
    if brdf_is_finite(pdf) {
        return pdf;
    }
    return 0.0;
}

// `Dielectric::sample`.
fn dielectric_sample(d: Dielectric, wo: vec3<f32>, uc: f32, u: vec2<f32>) -> ScatterSample {
    if !(wo.z != 0.0) || !(brdf_is_finite(wo.x) && brdf_is_finite(wo.y) && brdf_is_finite(wo.z)) {
        return scatter_none();
    }
    if d.iface == DIELECTRIC_SMOOTH {
        let fr = fresnel_dielectric(wo.z, d.eta);
        let rgb = dielectric_reflectance(d, fr, wo.z);
        let p = brdf_max_element(rgb);
        if uc < p {
            var w = vec3<f32>(1.0);
            // #if IRIDESCENCE
            if d.film_factor > 0.0 { w = rgb / p; }
            // #endif
            return ScatterSample(vec3<f32>(-wo.x, -wo.y, wo.z), p, w,
                                 dielectric_rescale(uc, p, true), true, false, true);
        }
        let wi = vec3<f32>(-fr.eta_ti * wo.x, -fr.eta_ti * wo.y, fr.cos_t);
        return ScatterSample(wi, 1.0 - p, d.tint * (fr.eta_ti * fr.eta_ti),
                             dielectric_rescale(uc, p, false), true, true, true);
    }
    if d.iface == DIELECTRIC_THIN {
        let rgb = dielectric_thin_reflectance(d, wo.z);
        let r = brdf_max_element(rgb);
        if uc < r {
            var w = vec3<f32>(1.0);
            // #if IRIDESCENCE
            if d.film_factor > 0.0 { w = rgb / r; }
            // #endif
            return ScatterSample(vec3<f32>(-wo.x, -wo.y, wo.z), r, w,
                                 dielectric_rescale(uc, r, true), true, false, true);
        }
        return ScatterSample(-wo, 1.0 - r, d.tint, dielectric_rescale(uc, r, false), true, true, true);
    }
    if d.iface == DIELECTRIC_ROUGH_THIN {
        return dielectric_sheet_sample(d, wo, uc, u);
    }
    let flip = select(-1.0, 1.0, wo.z > 0.0);
    let h = brdf_ggx_sample_vndf_caps(brdf_ggx_isotropic(d.alpha), wo * flip, u);
    let cos_oh = brdf_dot(wo, h);
    let fr = fresnel_dielectric(cos_oh, d.eta);
    let rgb = dielectric_reflectance(d, fr, cos_oh);
    let p = brdf_max_element(rgb);
    var wi: vec3<f32>;
    let transmitted = !(uc < p);
    if transmitted {
        wi = h * (cos_oh * fr.eta_ti + fr.cos_t) - wo * fr.eta_ti;
    } else {
        wi = brdf_reflect(wo, h);
    }
    if (wi.z * flip > 0.0) == transmitted || wi.z == 0.0 {
        return scatter_none();
    }
    wi = brdf_normalize_or(wi, vec3<f32>(0.0));
    let pdf = dielectric_pdf(d, wo, wi);
    if !(pdf > 0.0) {
        return scatter_none();
    }
    let weight = dielectric_g2_over_g1(d, wo, wi);
    var w = vec3<f32>(weight);
    if transmitted {
        var eta_ti = d.eta;
        if wo.z > 0.0 {
            eta_ti = 1.0 / d.eta;
        }
        w = d.tint * (weight * (eta_ti * eta_ti));
    }
    // #if IRIDESCENCE
    if !transmitted && d.film_factor > 0.0 { w = rgb * (weight / p); }
    // #endif
    return ScatterSample(wi, pdf, w, dielectric_rescale(uc, p, !transmitted), false, transmitted, true);
}

// `Dielectric::shadow_transmittance`: T′·tint for a sheet, the tint at η = 1, 0 otherwise.
fn dielectric_shadow_transmittance(d: Dielectric, cos: f32) -> vec3<f32> {
    if d.iface == DIELECTRIC_THIN {
        return d.tint * (1.0 - brdf_max_element(dielectric_thin_reflectance(d, cos)));
    }
    if d.iface == DIELECTRIC_SMOOTH && d.eta == 1.0 {
        return d.tint;
    }
    return vec3<f32>(0.0);
}

// `Dielectric::is_straight`: a transmitted ray goes on undeviated (a sheet, or η = 1).
fn dielectric_is_straight(d: Dielectric) -> bool {
    return d.iface == DIELECTRIC_THIN || (d.iface == DIELECTRIC_SMOOTH && d.eta == 1.0);
}

// `Transmissive`: the dielectric with probability `weight`, else the opaque BSDF.
struct Transmissive {
    d: Dielectric,
    opaque: BsdfParams,
    weight: f32,
}

fn transmissive_is_delta(t: Transmissive) -> bool {
    return t.weight >= 1.0 && !dielectric_is_rough(t.d);
}

fn transmissive_eval(t: Transmissive, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    var f = vec3<f32>(0.0);
    if dielectric_is_rough(t.d) {
        f += t.weight * dielectric_eval(t.d, wo, wi);
    }
    if t.weight < 1.0 {
        f += (1.0 - t.weight) * bsdf_eval(t.opaque, wo, wi);
    }
    return f;
}

fn transmissive_pdf(t: Transmissive, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    var p = 0.0;
    if dielectric_is_rough(t.d) {
        p += t.weight * dielectric_pdf(t.d, wo, wi);
    }
    if t.weight < 1.0 {
        p += (1.0 - t.weight) * bsdf_pdf(t.opaque, wo, wi);
    }
    return p;
}

fn transmissive_sample(t: Transmissive, wo: vec3<f32>, uc: f32, u: vec2<f32>) -> ScatterSample {
    let g = t.weight;
    if g >= 1.0 {
        return dielectric_sample(t.d, wo, uc, u);
    }
    var s: ScatterSample;
    if uc < g {
        s = dielectric_sample(t.d, wo, dielectric_rescale(uc, g, true), u);
        if !s.valid || s.delta {
            return s;
        }
    } else {
        let o = bsdf_sample(t.opaque, wo, dielectric_rescale(uc, g, false), u);
        if o.lobe == BSDF_LOBE_NONE {
            return scatter_none();
        }
        s = ScatterSample(o.wi, o.pdf, o.weight, 0.0, false, false, true);
    }
    let pdf = transmissive_pdf(t, wo, s.wi);
    if !brdf_positive_finite(pdf) {
        return scatter_none();
    }
    s.pdf = pdf;
    s.weight = transmissive_eval(t, wo, s.wi) / pdf;
    return s;
}
