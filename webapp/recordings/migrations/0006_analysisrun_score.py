from django.db import migrations, models
from django.db.models import FloatField
from django.db.models.fields.json import KT
from django.db.models.functions import Cast


def copy_scores(apps, schema_editor):
    """Fill the new column from the summaries of runs that already succeeded."""
    runs = apps.get_model("recordings", "AnalysisRun")
    runs.objects.filter(status="succeeded", summary__has_key="score").update(
        score=Cast(KT("summary__score"), FloatField())
    )


class Migration(migrations.Migration):
    dependencies = [
        ("recordings", "0005_scale_indexes"),
    ]

    operations = [
        migrations.AddField(
            model_name="analysisrun",
            name="score",
            field=models.FloatField(blank=True, null=True),
        ),
        migrations.RunPython(copy_scores, migrations.RunPython.noop),
    ]
