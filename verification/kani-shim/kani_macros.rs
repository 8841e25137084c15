//! Pass-through stand-ins for Kani's attribute macros, for
//! `check.sh`: a type check of the kernel's cfg(kani) code, not a verifier.
//! `stub(a, b)` also checks that both paths resolve: a free function's
//! whole path, a method's type (a generic method's path alone does not
//! type-check without its type arguments; Kani resolves the method when it
//! runs).
extern crate proc_macro;
use proc_macro::{TokenStream, TokenTree};
use std::str::FromStr;

#[proc_macro_attribute]
pub fn proof(_a: TokenStream, item: TokenStream) -> TokenStream {
    item
}
#[proc_macro_attribute]
pub fn unwind(_a: TokenStream, item: TokenStream) -> TokenStream {
    item
}
#[proc_macro_attribute]
pub fn stub(attr: TokenStream, item: TokenStream) -> TokenStream {
    let mut parts = vec![String::new()];
    for t in attr {
        match &t {
            TokenTree::Punct(p) if p.as_char() == ',' => parts.push(String::new()),
            _ => {
                let s = t.to_string();
                parts.last_mut().unwrap().push_str(&s);
            }
        }
    }
    assert_eq!(parts.len(), 2, "stub takes two paths");
    let mut checks = String::new();
    for p in &parts {
        let segs: Vec<&str> = p.split("::").collect();
        let method = segs.len() >= 2 && segs[segs.len() - 2].chars().next().unwrap().is_uppercase();
        if method {
            let ty = segs[..segs.len() - 1].join("::");
            checks.push_str(&format!("let _ = core::marker::PhantomData::<{ty}>;"));
        } else {
            checks.push_str(&format!("#[allow(unused_imports)] use {p} as _;"));
        }
    }
    let mut out = item.to_string();
    out.push_str(&format!(
        "#[allow(dead_code)] const _: () = {{ {checks} }};"
    ));
    TokenStream::from_str(&out).unwrap()
}
