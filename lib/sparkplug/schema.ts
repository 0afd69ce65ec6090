/**
 * The Sparkplug B payload schema as protobufjs reflection, written from the
 * field lists of the Sparkplug 3.0 specification, chapter 6 "Payloads"
 * (section "Google Protocol Buffer Schema", proto2): every field optional or
 * repeated, with the number the specification gives it. The `extension_value`
 * fields and `extensions` ranges carry nothing here, so they are left out
 * (an unknown field in a peer's payload is skipped by the decoder).
 *
 * Repeated scalars (DataSet.types) are unpacked, as proto2 has them; a decoder
 * accepts both forms.
 */
import * as protobuf from 'protobufjs';

type FieldSpec = [name: string, type: string, id: number, rule?: 'repeated'];

function fields(list: readonly FieldSpec[]): Record<string, protobuf.IField & { rule?: string }> {
  const out: Record<string, protobuf.IField & { rule?: string }> = {};
  for (const [name, type, id, rule] of list) {
    out[name] = rule ? { type, id, rule, options: { packed: false } } : { type, id, rule: 'optional' };
  }
  return out;
}

/** The value fields a Template parameter, a DataSet cell and a property share (their numbers differ). */
const SCALAR_VALUES = ['uint32', 'uint64', 'float', 'double', 'bool', 'string'] as const;
const SCALAR_NAMES = ['int_value', 'long_value', 'float_value', 'double_value', 'boolean_value', 'string_value'] as const;

function scalarFields(firstId: number): FieldSpec[] {
  return SCALAR_NAMES.map((name, i) => [name, SCALAR_VALUES[i]!, firstId + i]);
}

const DESCRIPTOR: protobuf.INamespace = {
  nested: {
    Payload: {
      // proto2, as the specification's schema: a field set to 0 or false (seq 0, alias 0) is still sent.
      edition: 'proto2',
      fields: fields([
        ['timestamp', 'uint64', 1],
        ['metrics', 'Metric', 2, 'repeated'],
        ['seq', 'uint64', 3],
        ['uuid', 'string', 4],
        ['body', 'bytes', 5],
      ]),
      nested: {
        Template: {
          fields: fields([
            ['version', 'string', 1],
            ['metrics', 'Metric', 2, 'repeated'],
            ['parameters', 'Parameter', 3, 'repeated'],
            ['template_ref', 'string', 4],
            ['is_definition', 'bool', 5],
          ]),
          nested: {
            Parameter: { fields: fields([['name', 'string', 1], ['type', 'uint32', 2], ...scalarFields(3)]) },
          },
        },
        DataSet: {
          fields: fields([
            ['num_of_columns', 'uint64', 1],
            ['columns', 'string', 2, 'repeated'],
            ['types', 'uint32', 3, 'repeated'],
            ['rows', 'Row', 4, 'repeated'],
          ]),
          nested: {
            DataSetValue: { fields: fields(scalarFields(1)) },
            Row: { fields: fields([['elements', 'DataSetValue', 1, 'repeated']]) },
          },
        },
        PropertyValue: {
          fields: fields([
            ['type', 'uint32', 1],
            ['is_null', 'bool', 2],
            ...scalarFields(3),
            ['propertyset_value', 'PropertySet', 9],
            ['propertysets_value', 'PropertySetList', 10],
          ]),
        },
        PropertySet: {
          fields: fields([
            ['keys', 'string', 1, 'repeated'],
            ['values', 'PropertyValue', 2, 'repeated'],
          ]),
        },
        PropertySetList: { fields: fields([['propertyset', 'PropertySet', 1, 'repeated']]) },
        MetaData: {
          fields: fields([
            ['is_multi_part', 'bool', 1],
            ['content_type', 'string', 2],
            ['size', 'uint64', 3],
            ['seq', 'uint64', 4],
            ['file_name', 'string', 5],
            ['file_type', 'string', 6],
            ['md5', 'string', 7],
            ['description', 'string', 8],
          ]),
        },
        Metric: {
          fields: fields([
            ['name', 'string', 1],
            ['alias', 'uint64', 2],
            ['timestamp', 'uint64', 3],
            ['datatype', 'uint32', 4],
            ['is_historical', 'bool', 5],
            ['is_transient', 'bool', 6],
            ['is_null', 'bool', 7],
            ['metadata', 'MetaData', 8],
            ['properties', 'PropertySet', 9],
            ['int_value', 'uint32', 10],
            ['long_value', 'uint64', 11],
            ['float_value', 'float', 12],
            ['double_value', 'double', 13],
            ['boolean_value', 'bool', 14],
            ['string_value', 'string', 15],
            ['bytes_value', 'bytes', 16],
            ['dataset_value', 'DataSet', 17],
            ['template_value', 'Template', 18],
          ]),
        },
      },
    },
  },
};

/** The Payload message type (org.eclipse.tahu.protobuf.Payload in the specification's package). */
export const PAYLOAD_TYPE: protobuf.Type = protobuf.Root.fromJSON(DESCRIPTOR).lookupType('Payload');
