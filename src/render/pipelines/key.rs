//! What a pipeline is built from, and how it is named in reports.

use std::collections::BTreeMap;

/// What a pipeline is built from; equal keys share one pipeline in the [`PipelineCache`].
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PipelineKey {
    /// The WGSL file, relative to the shader root.
    pub shader: String,
    /// `#define`s the shader was composed with (name to value).
    pub defines: BTreeMap<String, String>,
    /// Generated code's text (materials), part of the key so an edit rebuilds.
    pub virtual_code: BTreeMap<String, String>,
    /// Target formats, sample count, entry points...
    pub state: String,
}

impl PipelineKey {
    /// A short human description: shader, defines, and the material the generated code
    /// comes from (its first line names it), e.g.
    /// ``forward/forward.wgsl [LIGHT_LISTS=1] material `box` ``.
    pub fn describe(&self) -> String {
        let mut out = self.shader.clone();
        if !self.defines.is_empty() {
            let d: Vec<String> = self
                .defines
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            out.push_str(&format!(" [{}]", d.join(" ")));
        }
        for (name, code) in &self.virtual_code {
            let first = code.lines().next().unwrap_or("");
            match first.split('`').nth(1) {
                Some(material) => out.push_str(&format!(" {name} `{material}`")),
                None => out.push_str(&format!(" <{name}>")),
            }
        }
        if !self.state.is_empty() {
            out.push_str(&format!(" ({})", self.state));
        }
        out
    }

    /// The shader and the material its generated code comes from, without defines and
    /// state: ``forward/forward.wgsl `car_paint` ``.
    /// Without a material, the state (a compute pipeline's entry point) tells a shader's
    /// pipelines apart.
    pub fn short(&self) -> String {
        let mut out = self.shader.clone();
        let mut material = false;
        for code in self.virtual_code.values() {
            if let Some(name) = code.lines().next().unwrap_or("").split('`').nth(1) {
                out.push_str(&format!(" `{name}`"));
                material = true;
            }
        }
        if !material && !self.state.is_empty() {
            out.push_str(&format!(" ({})", self.state));
        }
        out
    }
}
