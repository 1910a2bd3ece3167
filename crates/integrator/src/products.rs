//! The products of a renderer's preparations (crate::prepare), held as a set keyed by type.
use std::any::Any;

/// What a renderer's preparations built, at most one of each type: the radiance cache
/// (`bdpm_cache::RadianceCache`), the noise model's, the pixel table, `corrected-balance`'s
/// factors, the radius map, the direct-light samples. A preparation puts its product here;
/// the passes, the noise model and the renderer's accessors get it by its type, once per
/// pass or query (never per sample), so a new preparation needs no field of its own.
#[derive(Default)]
pub(crate) struct Products {
    items: Vec<Box<dyn Any + Send + Sync>>,
}

impl Products {
    /// The product of type `T`, if one was built.
    pub(crate) fn get<T: Any>(&self) -> Option<&T> {
        self.items.iter().find_map(|i| i.downcast_ref::<T>())
    }

    /// Keeps `item`, in place of any product of its type.
    pub(crate) fn put(&mut self, item: Box<dyn Any + Send + Sync>) {
        let kind = Any::type_id(&*item);
        self.items.retain(|i| Any::type_id(&**i) != kind);
        self.items.push(item);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_are_found_by_type_and_replaced_by_their_type() {
        let mut p = Products::default();
        assert_eq!(p.get::<u32>(), None);
        p.put(Box::new(3u32));
        p.put(Box::new(String::from("x")));
        p.put(Box::new(4u32));
        assert_eq!(p.get::<u32>(), Some(&4));
        assert_eq!(p.get::<String>().map(String::as_str), Some("x"));
        assert_eq!(p.items.len(), 2);
    }
}
