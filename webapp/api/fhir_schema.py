"""The OpenAPI description of the FHIR R4 Bundle `webapp.api.exports.patient_bundle` writes:
exactly the FHIR elements it fills (a subset of FHIR R4's Bundle, Patient and Observation), each
object closed like every other object of the schema. Every FHIR answer the test suite receives
is validated against it (tests/webapp/openapi_check.py), so an element added to the export
without its description here fails the tests.
"""

from __future__ import annotations

from drf_spectacular.utils import PolymorphicProxySerializer
from rest_framework import serializers


class FhirCodingSerializer(serializers.Serializer):
    system = serializers.CharField()
    code = serializers.CharField()
    display = serializers.CharField()


class FhirCodeableConceptSerializer(serializers.Serializer):
    coding = FhirCodingSerializer(many=True)
    text = serializers.CharField(required=False)


class FhirAbsentReasonSerializer(serializers.Serializer):
    text = serializers.CharField(help_text="why there is no value (the recording does not fit)")


class FhirQuantitySerializer(serializers.Serializer):
    value = serializers.FloatField()
    unit = serializers.CharField()
    system = serializers.CharField(help_text="UCUM")
    code = serializers.CharField()


class FhirRangeSerializer(serializers.Serializer):
    low = FhirQuantitySerializer()
    high = FhirQuantitySerializer()


class FhirReferenceSerializer(serializers.Serializer):
    reference = serializers.CharField()


class FhirHumanNameSerializer(serializers.Serializer):
    text = serializers.CharField()


class FhirPatientSerializer(serializers.Serializer):
    resourceType = serializers.ChoiceField(["Patient"])  # noqa: N815 (FHIR's element name)
    id = serializers.CharField()
    active = serializers.BooleanField()
    name = FhirHumanNameSerializer(many=True)
    birthDate = serializers.DateField(required=False)  # noqa: N815


class FhirComponentSerializer(serializers.Serializer):
    code = FhirCodeableConceptSerializer()
    valueQuantity = FhirQuantitySerializer()  # noqa: N815


class FhirObservationSerializer(serializers.Serializer):
    resourceType = serializers.ChoiceField(["Observation"])  # noqa: N815
    id = serializers.CharField()
    status = serializers.ChoiceField(["final"])
    category = FhirCodeableConceptSerializer(many=True)
    subject = FhirReferenceSerializer()
    effectiveDateTime = serializers.CharField()  # noqa: N815
    code = FhirCodeableConceptSerializer()
    component = FhirComponentSerializer(many=True)
    # One of the three: a score, an angle's range, or why there is no score.
    valueQuantity = FhirQuantitySerializer(required=False)  # noqa: N815
    valueRange = FhirRangeSerializer(required=False)  # noqa: N815
    dataAbsentReason = FhirAbsentReasonSerializer(required=False)  # noqa: N815


class FhirEntrySerializer(serializers.Serializer):
    fullUrl = serializers.CharField()  # noqa: N815
    resource = PolymorphicProxySerializer(
        component_name="FhirResource",
        serializers={"Patient": FhirPatientSerializer, "Observation": FhirObservationSerializer},
        resource_type_field_name="resourceType",
    )


class FhirBundleSerializer(serializers.Serializer):
    """A FHIR R4 Bundle of type collection: the patient, then their recordings' Observations."""

    resourceType = serializers.ChoiceField(["Bundle"])  # noqa: N815
    id = serializers.CharField()
    type = serializers.ChoiceField(["collection"])
    timestamp = serializers.CharField()
    entry = FhirEntrySerializer(many=True)
