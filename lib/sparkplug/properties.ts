/**
 * PropertySet and PropertySetList (Sparkplug 3.0, sections 6.4.9–6.4.12):
 * keys and values in two parallel lists; a value is a scalar by its type, or
 * a nested PropertySet (20) or PropertySetList (21). Pure.
 */
import { PlcError, ValueError } from '../errors';
import { DataType } from './datatypes';
import type { PropertySet, PropertyValue } from './model';
import { isScalarType, scalarFields, scalarValue, type ScalarFields } from './scalars';

type Message = Record<string, unknown>;

export function encodePropertySet(set: PropertySet, what: string): Message {
  const keys = Object.keys(set);
  return { keys, values: keys.map((k) => encodePropertyValue(set[k]!, `${what} property ${k}`)) };
}

function encodePropertyValue(p: PropertyValue, what: string): Message {
  if (p.value === null) return { type: p.type, is_null: true };
  if (p.type === DataType.PropertySet) return { type: p.type, propertyset_value: encodePropertySet(p.value as PropertySet, what) };
  if (p.type === DataType.PropertySetList) {
    if (!Array.isArray(p.value)) throw new ValueError(what, 'a PropertySetList takes an array of property sets');
    return {
      type: p.type,
      propertysets_value: { propertyset: p.value.map((s, i) => encodePropertySet(s as PropertySet, `${what}[${i}]`)) },
    };
  }
  if (!isScalarType(p.type)) throw new ValueError(what, `a property cannot hold datatype ${p.type}`);
  return { type: p.type, ...scalarFields(p.type, p.value, what) };
}

export function decodePropertySet(m: Message, what: string): PropertySet {
  const keys = (m['keys'] as string[]) ?? [];
  const values = (m['values'] as Message[]) ?? [];
  if (keys.length !== values.length) {
    throw new PlcError(
      'PROTOCOL_ERROR',
      `Sparkplug payload: metric ${what}: a PropertySet of ${keys.length} keys and ${values.length} values`,
      { tag: what },
    );
  }
  const out: PropertySet = {};
  keys.forEach((k, i) => {
    out[k] = decodePropertyValue(values[i]!, `${what} property ${k}`);
  });
  return out;
}

function decodePropertyValue(v: Message, what: string): PropertyValue {
  const type = (v['type'] as number) ?? DataType.Unknown;
  if (v['is_null'] === true) return { type, value: null };
  if (type === DataType.PropertySet) return { type, value: decodePropertySet((v['propertyset_value'] as Message) ?? {}, what) };
  if (type === DataType.PropertySetList) {
    const list = ((v['propertysets_value'] as Message)?.['propertyset'] as Message[]) ?? [];
    return { type, value: list.map((s, i) => decodePropertySet(s, `${what}[${i}]`)) };
  }
  if (!isScalarType(type))
    throw new PlcError('PROTOCOL_ERROR', `Sparkplug payload: metric ${what}: a property of datatype ${type}`, { tag: what });
  return { type, value: scalarValue(type, v as ScalarFields, `metric ${what}`) };
}
